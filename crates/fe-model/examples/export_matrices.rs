//! Exports a case's model as another finite element code would: a Matrix
//! Market stiffness and mass file per group (and the damping file of a
//! group imported with one), over the free equations, with
//! the DOF table and the node coordinates. It made the worked example of
//! `docs/imported-models.md` (`cases/imported/`):
//!
//! ```text
//! cargo run -p fe-model --example export_matrices -- cases/table-frame.toml cases/imported table
//! ```

use std::path::Path;

use fe_model::imported::{export, matrix_market};
use fe_model::{Assembly, CaseFile};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [case, dir, prefix] = args.as_slice() else {
        return Err("usage: export_matrices CASE OUT_DIR PREFIX".into());
    };
    let case = CaseFile::load(case).map_err(|e| e.render())?;
    let model = &case.model;
    let exported = export::export(model, &Assembly::new(model)?);
    let dir = Path::new(dir);
    std::fs::create_dir_all(dir)?;
    let write = |name: String, text: String| -> std::io::Result<()> {
        println!("wrote {}", dir.join(&name).display());
        std::fs::write(dir.join(name), text)
    };
    write(format!("{prefix}-dofs.txt"), exported.dof_table())?;
    write(format!("{prefix}-nodes.txt"), export::node_file(model))?;
    for g in &exported.groups {
        let (group, from) = (&g.name, format!("group `{}` of {}", g.name, case.path.display()));
        write(format!("{prefix}-{group}-K.mtx"), matrix_market::write(&g.stiffness, &format!("stiffness of {from}")))?;
        write(format!("{prefix}-{group}-M.mtx"), matrix_market::write(&g.mass, &format!("mass of {from}")))?;
        if !g.damping.entries.is_empty() {
            let text = matrix_market::write(&g.damping, &format!("viscous damping of {from}"));
            write(format!("{prefix}-{group}-C.mtx"), text)?;
        }
    }
    Ok(())
}

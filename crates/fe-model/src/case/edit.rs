//! Edits of a case file that keep the user's layout and comments.
//!
//! `rfm diagnose --apply`, `rfm update` and `rfm fix` write new case files
//! (never over the input): the user's case with an effect added, values
//! merged into `[set]`, the parameters to update, and the history of the
//! misfit. The edits are made on the TOML document itself (`toml_edit`), so
//! that comments, order and layout stay as the user wrote them; added model
//! items are appended as text under a comment that says where they came
//! from. The paths of the measured data and of the test geometry are
//! rewritten relative to the new file's folder, so that a written case can
//! be moved together with its data, and every result is parsed again as a
//! case file before it is handed back.

use std::path::{Component, Path, PathBuf};

use toml_edit::{ArrayOfTables, DocumentMut, Item, Table, value};

use super::{CaseFile, FittedGain, Gains, HistoryEntry};
use crate::dof::DofRef;
use crate::error::CaseError;

/// An edit of a case file's text; see the module docs.
#[derive(Clone, Debug)]
pub struct CaseEditor {
    /// The case file being edited (messages; the base of its data path).
    path: PathBuf,
    /// Its measured-data file, resolved.
    data: Option<PathBuf>,
    /// Its test-geometry file, resolved.
    geometry: Option<PathBuf>,
    doc: DocumentMut,
}

impl CaseFile {
    /// An editor on this case's text, for a new case derived from it. The
    /// `[check]` table is left out: it is the acceptance of this case's own
    /// results (`cargo xtask reproduce`), which a case with added effects or
    /// updated values does not share.
    pub fn editor(&self) -> Result<CaseEditor, CaseError> {
        let mut doc = self.source.parse::<DocumentMut>().map_err(|e| self.error(e.span(), e.message().to_string()))?;
        doc.remove("check");
        let data = self.measurement.as_ref().and_then(|m| m.data.clone());
        let geometry = self.measurement.as_ref().and_then(|m| m.geometry.clone());
        Ok(CaseEditor { path: self.path.clone(), data, geometry, doc })
    }

    /// This case reading its measured FRFs from `data` instead of its own
    /// data file or `[truth]` (the `--measured` of `rfm update` and `rfm
    /// fix`): `[measurement] data` names it (relative to the case's folder
    /// when it can, as every case derived from this one then writes it),
    /// and the `[truth]` and `[check]`, which describe other data, are
    /// left out. The channels, lines, gains and corrections the case
    /// declares stay. The case keeps its path, for messages and for the
    /// other paths it names.
    pub fn with_data(&self, data: &Path) -> Result<CaseFile, CaseError> {
        self.reading(data, false)
    }

    /// As [`Self::with_data`], for data whose channels name the model's
    /// DOFs already (a file written from FRFs held in memory): the
    /// `[measurement]` map and pairing, which translate a test's own points
    /// and directions, are left out, here and in every case derived.
    pub fn with_model_dof_data(&self, data: &Path) -> Result<CaseFile, CaseError> {
        self.reading(data, true)
    }

    fn reading(&self, data: &Path, model_dofs: bool) -> Result<CaseFile, CaseError> {
        let absolute = std::path::absolute(data).map_err(|e| CaseError {
            file: self.path.clone(),
            location: None,
            message: format!("cannot resolve the measured data's path {}: {e}", data.display()),
            snippet: None,
        })?;
        let mut editor = self.editor()?;
        editor.use_data(&absolute);
        if model_dofs && let Some(m) = editor.doc.get_mut("measurement").and_then(Item::as_table_like_mut) {
            for key in ["map", "pair", "tolerance", "axes", "geometry"] {
                m.remove(key);
            }
            editor.geometry = None;
        }
        let text = editor.text_at(&self.path)?;
        let mut case = CaseFile::parse(&self.path, &text)?;
        // named as given in messages, not by the way up from the case's folder
        if let Some(m) = case.measurement.as_mut() {
            m.data = Some(absolute);
        }
        Ok(case)
    }
}

impl CaseEditor {
    /// An error about the edit (not located in the file).
    pub fn error(&self, message: String) -> CaseError {
        CaseError { file: self.path.clone(), location: None, message, snippet: None }
    }

    /// Removes every support entry of `node` (`[[supports]]` tables or
    /// inline entries); returns how many were removed.
    pub fn remove_supports_at(&mut self, node: u32) -> usize {
        let holds = |t: &dyn toml_edit::TableLike| {
            t.get("node").and_then(Item::as_integer).is_some_and(|n| n == i64::from(node))
        };
        match self.doc.get_mut("supports") {
            Some(Item::ArrayOfTables(a)) => {
                let before = a.len();
                a.retain(|t| !holds(t));
                before - a.len()
            }
            Some(Item::Value(toml_edit::Value::Array(a))) => {
                let before = a.len();
                a.retain(|v| !v.as_inline_table().is_some_and(|t| holds(t)));
                before - a.len()
            }
            _ => 0,
        }
    }

    /// Appends TOML text (new tables and array entries) under a comment
    /// line. Fails when the result is not valid TOML (a table defined twice).
    pub fn append(&mut self, comment: &str, snippet: &str) -> Result<(), CaseError> {
        let mut text = self.doc.to_string();
        while text.ends_with("\n\n") {
            text.pop();
        }
        if !text.is_empty() && !text.ends_with('\n') {
            text.push('\n');
        }
        text.push('\n');
        for line in comment.lines() {
            text.push_str(&format!("# {line}\n"));
        }
        text.push_str(snippet);
        self.doc = text.parse::<DocumentMut>().map_err(|e| {
            self.error(format!("the lines to add do not fit into the case file: {}", e.message().trim_end()))
        })?;
        Ok(())
    }

    /// Merges quantity values into the top-level `[set]` table (created when
    /// missing), with a comment above it.
    pub fn set_values(&mut self, values: &[(String, f64)], comment: &str) -> Result<(), CaseError> {
        if values.is_empty() {
            return Ok(());
        }
        let set = self.table("set")?;
        for (k, v) in values {
            set.insert(k, value(*v));
        }
        add_comment(set, comment);
        Ok(())
    }

    /// Sets what to update: the `[update]` table's parameters and method
    /// (created when missing; other keys of an existing table stay). Bounds
    /// of parameters no longer updated are removed.
    pub fn set_update(&mut self, parameters: &[String], method: &str) -> Result<(), CaseError> {
        let update = self.table("update")?;
        let mut list = toml_edit::Array::new();
        for p in parameters {
            list.push(p.as_str());
        }
        update.insert("parameters", value(list));
        update.insert("method", value(method));
        if let Some(bounds) = update.get_mut("bounds").and_then(Item::as_table_like_mut) {
            let stale: Vec<String> =
                bounds.iter().map(|(k, _)| k.to_string()).filter(|k| !parameters.contains(k)).collect();
            for k in stale {
                bounds.remove(&k);
            }
        }
        Ok(())
    }

    /// Makes the case read its measured FRFs from `path` (a file written
    /// beside the new case, holding the data the case synthesised from its
    /// `[truth]`), and removes the `[truth]` (and the `[check]`, which
    /// compares with it): once effects are added to the
    /// model, a truth defined on top of the model would no longer describe
    /// what was measured.
    pub fn use_data(&mut self, path: &Path) {
        self.data = Some(path.to_path_buf());
        self.doc.remove("truth");
        // the acceptance of the case's results compares them with the truth
        // it no longer has
        self.doc.remove("check");
        let measurement = self.doc.entry("measurement").or_insert(Item::Table(Table::new()));
        if let Some(m) = measurement.as_table_like_mut() {
            // a placeholder that `text_at` replaces by the path relative to the new file
            m.insert("data", value(path.to_string_lossy().as_ref()));
        }
    }

    /// Keeps the gains a run fitted: `[measurement] gains` set to the
    /// setting used (so that the next run fits them too, whatever decided
    /// it), and `fitted_gains` to their values (magnitude and phase in
    /// degrees), replacing earlier ones.
    pub fn set_gains(&mut self, gains: Gains, fitted: &[FittedGain]) -> Result<(), CaseError> {
        let m = self.table("measurement")?;
        m.insert("gains", value(gains.name()));
        if fitted.is_empty() {
            m.remove("fitted_gains");
            return Ok(());
        }
        let mut t = toml_edit::InlineTable::new();
        for g in fitted {
            let mut pair = toml_edit::Array::new();
            pair.push(g.magnitude);
            pair.push(g.phase_deg);
            t.insert(g.key.to_string(), toml_edit::Value::Array(pair));
        }
        m.insert("fitted_gains", value(t));
        Ok(())
    }

    /// Appends a correction of a set-up error to `[[measurement.corrections]]`
    /// (see [`super::ChannelCorrection`]): the channel at `response` (of
    /// `reference`, or of every reference), its `sign`, `scale` and the DOF
    /// its sensor `measured_at`, each written only when it changes
    /// something, and `why` as the entry's reason.
    ///
    /// A second correction of a channel (the same `response` and
    /// `reference`) is composed into its entry (signs and scales
    /// multiplied, the later `measured_at` kept, both reasons), since the
    /// case allows one entry per channel; two that undo each other leave
    /// none.
    pub fn add_correction(
        &mut self,
        response: DofRef,
        reference: Option<DofRef>,
        sign: f64,
        scale: f64,
        measured_at: Option<DofRef>,
        why: &str,
    ) -> Result<(), CaseError> {
        // (an `Item`'s own `get_mut` would insert the key it does not find)
        if let Some(Item::ArrayOfTables(a)) =
            self.doc.get_mut("measurement").and_then(Item::as_table_like_mut).and_then(|m| m.get_mut("corrections"))
        {
            let text = |t: &Table, k: &str| t.get(k).and_then(Item::as_str).map(str::to_string);
            let number = |t: &Table, k: &str| {
                t.get(k).and_then(|v| v.as_float().or_else(|| v.as_integer().map(|i| i as f64))).unwrap_or(1.0)
            };
            let (response_s, reference_s) = (response.to_string(), reference.map(|r| r.to_string()));
            let earlier = a.iter().position(|t| {
                text(t, "response").as_deref() == Some(response_s.as_str()) && text(t, "reference") == reference_s
            });
            if let Some(i) = earlier {
                let t = a.get_mut(i).expect("found above");
                let (sign, scale) = (number(t, "sign") * sign, number(t, "scale") * scale);
                for (key, v, unit) in [("sign", sign, 1.0), ("scale", scale, 1.0)] {
                    if v == unit {
                        t.remove(key);
                    } else {
                        t.insert(key, value(v));
                    }
                }
                if let Some(d) = measured_at {
                    t.insert("measured_at", value(d.to_string()));
                }
                let reason = text(t, "why").map_or_else(|| why.to_string(), |w| format!("{w}; then {why}"));
                t.insert("why", value(reason));
                // two corrections that undo each other leave the channel as read
                if ["sign", "scale", "measured_at"].iter().all(|k| !t.contains_key(k)) {
                    a.remove(i);
                }
                return Ok(());
            }
        }
        let mut t = Table::new();
        t.insert("response", value(response.to_string()));
        if let Some(r) = reference {
            t.insert("reference", value(r.to_string()));
        }
        if sign != 1.0 {
            t.insert("sign", value(sign));
        }
        if scale != 1.0 {
            t.insert("scale", value(scale));
        }
        if let Some(d) = measured_at {
            t.insert("measured_at", value(d.to_string()));
        }
        t.insert("why", value(why));
        let err = self.error("`measurement.corrections` is not a list of [[measurement.corrections]] tables".into());
        let m = self.table("measurement")?;
        match m.entry("corrections").or_insert(Item::ArrayOfTables(ArrayOfTables::new())) {
            Item::ArrayOfTables(a) => {
                if a.is_empty() {
                    t.decor_mut()
                        .set_prefix("\n# Set-up errors of the test, corrected after reading (written by rfm)\n");
                }
                a.push(t);
                Ok(())
            }
            _ => Err(err),
        }
    }

    /// Replaces the `[[history]]` of the misfit by `entries` (a history
    /// rebuilt from a case before it, where the case was rebuilt from its
    /// nominal one: `rfm fix`'s revisions).
    pub fn set_history(&mut self, entries: &[HistoryEntry]) -> Result<(), CaseError> {
        self.doc.remove("history");
        for e in entries {
            self.push_history(e)?;
        }
        Ok(())
    }

    /// Appends an entry to the `[[history]]` of the misfit.
    pub fn push_history(&mut self, entry: &HistoryEntry) -> Result<(), CaseError> {
        let mut t = Table::new();
        t.insert("step", value(entry.step.as_str()));
        t.insert("misfit", value(entry.misfit));
        if let Some(noise) = entry.noise {
            t.insert("noise", value(noise));
        }
        if let Some(effect) = &entry.effect {
            t.insert("effect", value(effect.as_str()));
        }
        for (key, ids) in [("nodes", &entry.nodes), ("elements", &entry.elements)] {
            if !ids.is_empty() {
                t.insert(key, value(ids.iter().map(|&i| i64::from(i)).collect::<toml_edit::Array>()));
            }
        }
        match self.doc.entry("history").or_insert(Item::ArrayOfTables(ArrayOfTables::new())) {
            Item::ArrayOfTables(a) => {
                if a.is_empty() {
                    t.decor_mut().set_prefix(
                        "\n# The misfit after each step (RMS of ln(model / measured) per value), written by rfm\n",
                    );
                }
                a.push(t);
                Ok(())
            }
            _ => Err(self.error("`history` is not a list of [[history]] tables".into())),
        }
    }

    /// The edited text for a case file at `target`: the paths of the
    /// measured data and the test geometry made relative to `target`'s
    /// folder, parsed again as a case file.
    pub fn text_at(&self, target: &Path) -> Result<String, CaseError> {
        let mut doc = self.doc.clone();
        for (key, file) in [("data", &self.data), ("geometry", &self.geometry)] {
            let Some(file) = file else { continue };
            let rel = relative_path(file, target.parent().unwrap_or(Path::new("")));
            let rel = rel.to_string_lossy().replace('\\', "/");
            if let Some(m) = doc.get_mut("measurement").and_then(Item::as_table_like_mut)
                && let Some(d) = m.get_mut(key)
            {
                let decor = d.as_value().map(|v| v.decor().clone());
                *d = value(rel);
                if let (Some(decor), Some(v)) = (decor, d.as_value_mut()) {
                    *v.decor_mut() = decor;
                }
            }
        }
        rewrite_imported_paths(&mut doc, self.path.parent().unwrap_or(Path::new("")), target);
        let text = doc.to_string();
        CaseFile::parse(target, &text)?;
        Ok(text)
    }

    /// A top-level table, created when missing.
    fn table(&mut self, key: &str) -> Result<&mut Table, CaseError> {
        let err = self.error(format!("`{key}` is not a table"));
        let item = self.doc.entry(key).or_insert(Item::Table(Table::new()));
        if let Item::Value(toml_edit::Value::InlineTable(t)) = item {
            *item = Item::Table(std::mem::take(t).into_table());
        }
        item.as_table_mut().ok_or(err)
    }
}

/// The paths of `[imported]` (its node file, and each group's DOF table
/// and matrices), written relative to the case's folder `base`, rewritten
/// relative to the new file `target`'s, with their comments kept.
fn rewrite_imported_paths(doc: &mut DocumentMut, base: &Path, target: &Path) {
    let to = target.parent().unwrap_or(Path::new(""));
    let rewrite = |v: &mut toml_edit::Value| {
        let Some(s) = v.as_str() else { return };
        let p = Path::new(s);
        let file = if p.is_absolute() { p.to_path_buf() } else { base.join(p) };
        let rel = relative_path(&file, to).to_string_lossy().replace('\\', "/");
        let decor = v.decor().clone();
        *v = toml_edit::Value::from(rel);
        *v.decor_mut() = decor;
    };
    let Some(imported) = doc.get_mut("imported").and_then(Item::as_table_like_mut) else { return };
    if let Some(v) = imported.get_mut("nodes").and_then(Item::as_value_mut) {
        rewrite(v);
    }
    if let Some(Item::ArrayOfTables(groups)) = imported.get_mut("groups") {
        for t in groups.iter_mut() {
            for key in ["dofs", "stiffness", "mass", "damping"] {
                if let Some(v) = t.get_mut(key).and_then(Item::as_value_mut) {
                    rewrite(v);
                }
            }
        }
    }
}

/// Adds comment lines above a table, after any comment it has.
fn add_comment(t: &mut Table, comment: &str) {
    if comment.is_empty() {
        return;
    }
    let old = t.decor().prefix().and_then(|p| p.as_str()).unwrap_or("\n").to_string();
    let mut prefix = old.trim_end_matches(' ').to_string();
    if !prefix.ends_with('\n') {
        prefix.push('\n');
    }
    for line in comment.lines() {
        prefix.push_str(&format!("# {line}\n"));
    }
    t.decor_mut().set_prefix(prefix);
}

/// `path` relative to the folder `base`, through their common ancestor;
/// `path` itself (absolute) when they share none (another drive).
pub(crate) fn relative_path(path: &Path, base: &Path) -> PathBuf {
    let (path, base) = (resolved(path), resolved(base));
    let (p, b): (Vec<Component<'_>>, Vec<Component<'_>>) = (path.components().collect(), base.components().collect());
    let common = p.iter().zip(&b).take_while(|(x, y)| x == y).count();
    if common == 0 {
        return path;
    }
    let mut out = PathBuf::new();
    for _ in common..b.len() {
        out.push("..");
    }
    for c in &p[common..] {
        out.push(c);
    }
    out
}

/// An absolute path without `.` or `..`, through symbolic links where the
/// path (or its nearest existing ancestor) exists.
fn resolved(path: &Path) -> PathBuf {
    // the folder of a bare file name (`out.toml`) is the empty path, which
    // `absolute` refuses: it is the current folder
    let path = if path.as_os_str().is_empty() { Path::new(".") } else { path };
    let abs = std::path::absolute(path).unwrap_or_else(|_| path.to_path_buf());
    let mut clean = PathBuf::new();
    for c in abs.components() {
        match c {
            Component::CurDir => {}
            Component::ParentDir => {
                clean.pop();
            }
            other => clean.push(other),
        }
    }
    // the nearest ancestor that exists, with its links resolved
    let mut existing = clean.clone();
    let mut rest = Vec::new();
    while !existing.exists() {
        match existing.file_name() {
            Some(name) => rest.push(name.to_os_string()),
            None => return clean,
        }
        if !existing.pop() {
            return clean;
        }
    }
    let mut out = existing.canonicalize().unwrap_or(existing);
    for name in rest.into_iter().rev() {
        out.push(name);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    const CASE: &str = include_str!("../../tests/cases/edit-me.toml");

    fn case(dir: &Path) -> CaseFile {
        CaseFile::parse(&dir.join("case.toml"), CASE).unwrap()
    }

    #[test]
    fn data_paths_are_written_relative_to_the_new_file() {
        let dir = std::env::temp_dir().join(format!("rfm-edit-{}", std::process::id()));
        let c = case(&dir.join("study"));
        let e = c.editor().unwrap();
        let same = e.text_at(&dir.join("study/new.toml")).unwrap();
        assert!(same.contains("data = \"data/measured.csv\"   # from the lab"), "{same}");
        let deeper = e.text_at(&dir.join("study/out/step-1/new.toml")).unwrap();
        assert!(deeper.contains("data = \"../../data/measured.csv\""), "{deeper}");
        let beside = e.text_at(&dir.join("other/new.toml")).unwrap();
        assert!(beside.contains("data = \"../study/data/measured.csv\""), "{beside}");
        // the rewritten path names the same file
        let back = CaseFile::parse(&dir.join("other/new.toml"), &beside).unwrap();
        let got = back.measurement.unwrap().data.unwrap();
        assert_eq!(resolved(&got), resolved(&dir.join("study/data/measured.csv")));
        assert!(same.contains("# the user's comment"), "comments stay");
    }

    /// The case with other data names them relative to its folder, keeps
    /// its channels and comments, and drops the truth that described its
    /// own.
    #[test]
    fn a_case_reads_other_data_as_its_own() {
        let dir = std::env::temp_dir().join(format!("rfm-with-data-{}", std::process::id()));
        let c = case(&dir.join("study"));
        let other = c.with_data(&dir.join("lab/run-2.uff")).unwrap();
        let m = other.measurement.as_ref().unwrap();
        assert_eq!(resolved(m.data.as_ref().unwrap()), resolved(&dir.join("lab/run-2.uff")));
        assert_eq!(m.responses, c.measurement.as_ref().unwrap().responses);
        // (the old file's comment on its line goes with it)
        assert!(other.source.contains("data = \"../lab/run-2.uff\"\n"), "{}", other.source);
        assert!(other.source.contains("# the user's comment"), "comments stay");
        assert!(other.truth.is_none() && other.check.is_none());
        // a step derived from it reads the same file
        let step = other.editor().unwrap().text_at(&dir.join("study/out/step-1.toml")).unwrap();
        assert!(step.contains("data = \"../../lab/run-2.uff\""), "{step}");
    }

    /// Data in model DOFs drop the map that translates a test's points.
    #[test]
    fn data_in_model_dofs_are_read_without_the_map() {
        let dir = std::env::temp_dir().join(format!("rfm-model-dofs-{}", std::process::id()));
        let text = format!("{CASE}\n[[measurement.map]]\ntest = \"101:+Y\"\nmodel = \"2:ux\"\n");
        let c = CaseFile::parse(&dir.join("study/case.toml"), &text).unwrap();
        assert_eq!(c.measurement.as_ref().unwrap().map.len(), 1);
        let kept = c.with_data(&dir.join("lab/run.uff")).unwrap();
        assert_eq!(kept.measurement.as_ref().unwrap().map.len(), 1, "a test's file keeps the map");
        let own = c.with_model_dof_data(&dir.join("lab/run.uff")).unwrap();
        assert!(own.measurement.as_ref().unwrap().map.is_empty());
        assert!(!own.source.contains("measurement.map"), "{}", own.source);
        let step = own.editor().unwrap().text_at(&dir.join("study/out/step-1.toml")).unwrap();
        assert!(!step.contains("measurement.map") && step.contains("data = \"../../lab/run.uff\""), "{step}");
    }

    /// A correction of a channel corrected before is composed into the
    /// channel's one entry, and two that undo each other leave none; the
    /// two entries of a swap stay two.
    #[test]
    fn a_later_correction_of_a_channel_is_composed_into_its_entry() {
        let dir = std::env::temp_dir().join(format!("rfm-correct-{}", std::process::id()));
        let c = case(&dir);
        let ux = |n| DofRef::new(n, crate::dof::Dof::Ux);
        let mut e = c.editor().unwrap();
        e.add_correction(ux(3), Some(ux(5)), 1.0, 1.0, Some(ux(4)), "at node 4").unwrap();
        e.add_correction(ux(2), None, -1.0, 1.0, None, "inverted").unwrap();
        // the moved channel turns out inverted too
        e.add_correction(ux(3), Some(ux(5)), -1.0, 1.25, None, "inverted too").unwrap();
        // and the inverted one was not
        e.add_correction(ux(2), None, -1.0, 1.0, None, "not inverted after all").unwrap();
        // a swap: each channel at the other's DOF
        e.add_correction(ux(2), Some(ux(5)), 1.0, 1.0, Some(ux(5)), "swapped").unwrap();
        e.add_correction(ux(5), Some(ux(5)), 1.0, 1.0, Some(ux(2)), "swapped").unwrap();
        let text = e.text_at(&dir.join("case.toml")).unwrap();
        assert_eq!(text.matches("[[measurement.corrections]]").count(), 3, "{text}");
        let back = CaseFile::parse(&dir.join("case.toml"), &text).unwrap();
        let m = back.measurement.unwrap();
        let k = &m.corrections[0];
        assert_eq!(
            (k.response, k.reference, k.sign, k.scale, k.measured_at),
            (ux(3), Some(ux(5)), -1.0, 1.25, Some(ux(4)))
        );
        assert_eq!(k.why.as_deref(), Some("at node 4; then inverted too"));
    }

    /// A derived case does not inherit the shipped case's acceptance.
    #[test]
    fn the_check_table_is_not_carried_into_a_derived_case() {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../cases/two-material-beam.toml");
        let c = CaseFile::load(&path).unwrap();
        assert!(c.check.is_some() && c.source.contains("[check"));
        let text = c.editor().unwrap().text_at(&path.with_file_name("derived.toml")).unwrap();
        assert!(!text.contains("[check"), "{text}");
        let back = CaseFile::parse(&path.with_file_name("derived.toml"), &text).unwrap();
        assert!(back.check.is_none());
        assert_eq!(back.model.nodes().len(), c.model.nodes().len());
    }

    #[test]
    fn supports_of_one_node_are_removed_and_others_stay() {
        let c = case(Path::new("/tmp"));
        let mut e = c.editor().unwrap();
        assert_eq!(e.remove_supports_at(1), 1);
        assert_eq!(e.remove_supports_at(3), 0);
        e.append(
            "a spring instead",
            "[[springs]]\nname = \"s\"\nnode = 1\nkx = 1e9\nky = 1e9\nkr = 1e4\ngroup = \"beam\"\n",
        )
        .unwrap();
        let text = e.text_at(Path::new("/tmp/x.toml")).unwrap();
        let back = CaseFile::parse(Path::new("/tmp/x.toml"), &text).unwrap();
        assert_eq!(back.model.supports().len(), 1);
        assert_eq!(back.model.supports()[0].node.0, 5);
        assert!(text.contains("# a spring instead\n[[springs]]"), "{text}");
        // inline support lists are edited too
        let inline = CASE.replace("[[supports]]\nnode = 1\n[[supports]]\nnode = 5\ndofs = [\"uy\"]\n", "").replace(
            "title = \"edit me\"",
            "title = \"edit me\"\nsupports = [{ node = 1 }, { node = 5, dofs = [\"uy\"] }]",
        );
        let c = CaseFile::parse(Path::new("/tmp/case.toml"), &inline).unwrap();
        let mut e = c.editor().unwrap();
        assert_eq!(e.remove_supports_at(5), 1);
        assert!(!e.doc.to_string().contains("node = 5"));
    }

    #[test]
    fn values_merge_into_set_and_read_back_exactly() {
        let text = format!("{CASE}\n[set]\n\"group.beam.alpha\" = 2e-5   # measured\n");
        let c = CaseFile::parse(Path::new("/tmp/case.toml"), &text).unwrap();
        let mut e = c.editor().unwrap();
        let v = 3.141592653589793e-5;
        e.set_values(&[("group.beam.alpha".into(), v), ("group.beam.beta".into(), 0.25)], "updated by rfm").unwrap();
        let out = e.text_at(Path::new("/tmp/x.toml")).unwrap();
        assert_eq!(out.matches("[set]").count(), 1, "{out}");
        let back = CaseFile::parse(Path::new("/tmp/x.toml"), &out).unwrap();
        for (name, want) in [("group.beam.alpha", v), ("group.beam.beta", 0.25)] {
            let q = back.model.quantity(name).unwrap();
            assert_eq!(back.model.get(q), want, "{name}");
        }
        assert!(out.contains("# updated by rfm\n[set]"), "{out}");
    }

    /// A history entry may name only the effects there are: another name is
    /// refused with the file, the entry's place and a hint. Its nodes and
    /// elements record where an effect was put when it was added, and the
    /// model may have lost them since (the effect taken out again by hand or
    /// by `rfm fix`'s revision): the case loads with them as written.
    #[test]
    fn a_history_entry_is_checked_for_its_effect_not_for_places_since_gone() {
        let c = case(Path::new("/tmp"));
        let base = c.editor().unwrap().text_at(Path::new("/tmp/x.toml")).unwrap();
        let with = |entry: &str| format!("{base}\n[[history]]\nstep = \"+ x\"\nmisfit = 0.1\n{entry}\n");
        for (entry, says) in [
            ("effect = \"flexible joint\"", "the unknown effect `flexible joint`; did you mean `flexible_joint`?"),
            ("effect = \"crack\"", "the unknown effect `crack` (effects: flexible_support, flexible_joint,"),
        ] {
            let text = with(entry);
            // the entry's place: its `[[history]]` line (1-based)
            let line = text.lines().position(|l| l == "[[history]]").unwrap() + 1;
            let e = CaseFile::parse(Path::new("/tmp/x.toml"), &text).unwrap_err().to_string();
            assert!(e.contains(says), "{entry}: {e}");
            assert!(e.contains(&format!("x.toml:{line}:")), "{entry}: not located at line {line}: {e}");
        }
        let gone = CaseFile::parse(Path::new("/tmp/x.toml"), &with("nodes = [1, 999]\nelements = [999]")).unwrap();
        let h = gone.history.last().unwrap();
        assert_eq!((&h.nodes[..], &h.elements[..]), (&[1, 999][..], &[999][..]));
    }

    #[test]
    fn update_and_history_tables_are_written_and_parsed() {
        let c = case(Path::new("/tmp"));
        let mut e = c.editor().unwrap();
        e.set_update(&["group.beam.alpha".to_string()], "output-error").unwrap();
        e.push_history(&HistoryEntry { step: "nominal".into(), misfit: 1.25, noise: Some(0.01), ..Default::default() })
            .unwrap();
        let joint = HistoryEntry {
            step: "+ a joint".into(),
            misfit: 0.0125,
            noise: None,
            effect: Some("flexible_joint".into()),
            nodes: vec![3],
            elements: vec![2, 3],
        };
        e.push_history(&joint).unwrap();
        let out = e.text_at(Path::new("/tmp/x.toml")).unwrap();
        let back = CaseFile::parse(Path::new("/tmp/x.toml"), &out).unwrap();
        assert_eq!(back.update.as_ref().unwrap().parameters[0].name, "group.beam.alpha");
        assert_eq!(back.history.len(), 2);
        assert_eq!((back.history[0].step.as_str(), back.history[0].misfit), ("nominal", 1.25));
        assert_eq!((back.history[1].misfit, back.history[1].noise), (0.0125, None));
        // where the effect sits comes back; a step without one has none
        assert_eq!(back.history[1], joint);
        assert_eq!((back.history[0].effect.as_ref(), back.history[0].nodes.len()), (None, 0));
        // a history set anew replaces the old one, entry for entry
        let mut again = back.editor().unwrap();
        let rebuilt = [back.history[0].clone(), HistoryEntry { step: "updated after step 1".into(), ..joint.clone() }];
        again.set_history(&rebuilt).unwrap();
        let out = again.text_at(Path::new("/tmp/y.toml")).unwrap();
        assert_eq!(out.matches("[[history]]").count(), 2, "{out}");
        assert_eq!(CaseFile::parse(Path::new("/tmp/y.toml"), &out).unwrap().history, rebuilt);
    }

    #[test]
    fn a_synthesised_case_is_turned_into_one_that_reads_its_data() {
        let text = CASE.replace("data = \"data/measured.csv\"   # from the lab\n", "") + "[truth]\nnoise = 0.01\n";
        let c = CaseFile::parse(Path::new("/tmp/study/case.toml"), &text).unwrap();
        assert!(c.truth.is_some());
        let mut e = c.editor().unwrap();
        e.use_data(Path::new("/tmp/study/out/measured.csv"));
        let out = e.text_at(Path::new("/tmp/study/out/step-1.toml")).unwrap();
        let back = CaseFile::parse(Path::new("/tmp/study/out/step-1.toml"), &out).unwrap();
        assert!(back.truth.is_none(), "{out}");
        assert!(out.contains("data = \"measured.csv\""), "{out}");
    }

    #[test]
    fn an_addition_that_clashes_is_refused_with_its_reason() {
        let c = case(Path::new("/tmp"));
        let mut e = c.editor().unwrap();
        let err = e.append("again", "[groups.beam]\nalpha = 1\n").unwrap_err();
        assert!(err.message.contains("do not fit into the case file"), "{err}");
    }

    #[test]
    fn relative_paths_walk_up_to_the_common_folder() {
        assert_eq!(relative_path(Path::new("/a/b/c.csv"), Path::new("/a/b")), PathBuf::from("c.csv"));
        assert_eq!(relative_path(Path::new("/a/b/c.csv"), Path::new("/a/d/e")), PathBuf::from("../../b/c.csv"));
        assert_eq!(relative_path(Path::new("/a/./b/../b/c.csv"), Path::new("/a")), PathBuf::from("b/c.csv"));
    }

    /// `--out lap-with-joint.toml`: the new case's folder is the empty
    /// path, the current folder, and its data path stays relative.
    #[test]
    fn the_folder_of_a_bare_file_name_is_the_current_one() {
        let here = std::env::current_dir().expect("current folder");
        let data = here.join("data").join("measured.uff");
        let target = Path::new("out.toml");
        assert_eq!(relative_path(&data, target.parent().expect("a parent")), PathBuf::from("data/measured.uff"));
    }
}

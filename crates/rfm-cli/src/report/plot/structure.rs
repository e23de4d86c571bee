//! The structure drawn to scale: beams, supports, joints, springs, masses
//! and resonators (a mass on a spring beside its node), the measured DOFs
//! as arrows, and highlighted places (the
//! effects the loop added); and mode shapes drawn on it, deformed over
//! undeformed.
//!
//! Drawing is in pixels on an equal-scale view of the model's x-y plane
//! ([`View`]), so that a frame looks like the frame. A 3D model is drawn in
//! a cabinet projection ([`project`]): the x-y plane true to scale, as a
//! planar model, and z receding up and to the right at half scale, so that
//! a planar frame built in space looks as it does in the plane.

use std::collections::HashMap;

use fe_model::{Dimension, Dof, DofRef, Model, NodeId, PerDof};
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use super::projection::{RECEDING, deformed_beam_3d, imported_edges, project};
use super::{AXIS, Area, DrawResult, FONT, LegendEntry, MEASURED, Mark, PlotError, UPDATED, WIDTH, frame, svg};

/// Colour of the beams.
const BEAM: RGBColor = RGBColor(70, 70, 70);
/// Colour of the undeformed structure under a mode shape.
const UNDEFORMED: RGBColor = RGBColor(200, 200, 200);
/// Colour of the measured responses' arrows.
pub(crate) const RESPONSE: RGBColor = RGBColor(0, 158, 115);
/// Colour of the excitation arrows.
pub(crate) const EXCITATION: RGBColor = RGBColor(213, 94, 0);
/// Colours of the highlighted places, in order.
pub(crate) const HIGHLIGHTS: [RGBColor; 5] = [
    RGBColor(204, 37, 41),
    RGBColor(51, 34, 136),
    RGBColor(204, 121, 167),
    RGBColor(0, 114, 178),
    RGBColor(153, 153, 51),
];

/// An equal-scale map from model coordinates (m) to pixels.
#[derive(Clone, Copy, Debug)]
struct View {
    x0: f64,
    y0: f64,
    scale: f64,
    px0: f64,
    py0: f64,
}

impl View {
    /// The view that fits the box `(xmin, ymin, xmax, ymax)` centred into a
    /// `w` x `h` pixel area with `margin` pixels around it.
    fn fit(bbox: (f64, f64, f64, f64), w: f64, h: f64, margin: f64) -> Self {
        let (xmin, ymin, xmax, ymax) = bbox;
        let (dx, dy) = ((xmax - xmin).max(1e-12), (ymax - ymin).max(1e-12));
        let sx = (w - 2.0 * margin).max(10.0) / dx;
        let sy = (h - 2.0 * margin).max(10.0) / dy;
        let scale = sx.min(sy);
        let px0 = 0.5 * w - 0.5 * (xmin + xmax) * scale;
        let py0 = 0.5 * h + 0.5 * (ymin + ymax) * scale;
        View { x0: 0.0, y0: 0.0, scale, px0, py0 }
    }

    fn px(&self, x: f64, y: f64) -> (i32, i32) {
        let px = self.px0 + (x - self.x0) * self.scale;
        let py = self.py0 - (y - self.y0) * self.scale;
        (px.round() as i32, py.round() as i32)
    }
}

/// Bounding box of the nodes, grown to a square's tenth of the larger side
/// when the structure is a line (a beam along x has no height).
fn bbox(model: &Model) -> (f64, f64, f64, f64) {
    let (mut xmin, mut ymin, mut xmax, mut ymax) = (f64::INFINITY, f64::INFINITY, f64::NEG_INFINITY, f64::NEG_INFINITY);
    for n in model.nodes() {
        let (x, y) = project(model, n.position());
        xmin = xmin.min(x);
        xmax = xmax.max(x);
        ymin = ymin.min(y);
        ymax = ymax.max(y);
    }
    if !xmin.is_finite() {
        return (0.0, 0.0, 1.0, 1.0);
    }
    let size = (xmax - xmin).max(ymax - ymin).max(1e-9);
    let grow = |lo: f64, hi: f64| {
        let pad = (0.1 * size - (hi - lo)).max(0.0) / 2.0;
        (lo - pad, hi + pad)
    };
    let (xmin, xmax) = grow(xmin, xmax);
    let (ymin, ymax) = grow(ymin, ymax);
    (xmin, ymin, xmax, ymax)
}

/// Ratio of height to width of a structure's box, bounded for drawing.
fn aspect(model: &Model) -> f64 {
    let (xmin, ymin, xmax, ymax) = bbox(model);
    ((ymax - ymin) / (xmax - xmin)).clamp(0.1, 3.0)
}

fn node_xy(model: &Model, id: NodeId) -> Option<(f64, f64)> {
    model.node(id).map(|n| project(model, n.position()))
}

/// Unit direction (model axes) from a node along its first beam, or up.
fn beam_direction(model: &Model, id: NodeId) -> (f64, f64) {
    let Some((x, y)) = node_xy(model, id) else { return (0.0, 1.0) };
    for &b in &model.beams_at(id) {
        let beam = &model.beams()[b];
        let other = if beam.nodes[0] == id { beam.nodes[1] } else { beam.nodes[0] };
        if let Some((ox, oy)) = node_xy(model, other) {
            let (dx, dy) = (ox - x, oy - y);
            let l = (dx * dx + dy * dy).sqrt();
            if l > 0.0 {
                return (dx / l, dy / l);
            }
        }
    }
    (0.0, 1.0)
}

/// Pixel direction of a model direction (y flips).
fn pixel_dir(d: (f64, f64)) -> (f64, f64) {
    (d.0, -d.1)
}

fn add(p: (i32, i32), d: (f64, f64), len: f64) -> (i32, i32) {
    (p.0 + (d.0 * len).round() as i32, p.1 + (d.1 * len).round() as i32)
}

/// A ground: a wall across `dir` (pixels, pointing away from the
/// structure) through `p`, hatched on the far side.
fn draw_ground(area: &Area<'_>, p: (i32, i32), dir: (f64, f64), half: f64) -> DrawResult {
    let across = (-dir.1, dir.0);
    let a = add(p, across, half);
    let b = add(p, across, -half);
    area.draw(&PathElement::new(vec![a, b], BEAM.stroke_width(3)))?;
    let n = 5;
    for k in 0..=n {
        let t = -half + 2.0 * half * f64::from(k) / f64::from(n);
        let s = add(p, across, t);
        // hatches slant away from the structure
        let e = (s.0 + ((dir.0 + across.0) * 7.0) as i32, s.1 + ((dir.1 + across.1) * 7.0) as i32);
        area.draw(&PathElement::new(vec![s, e], BEAM.stroke_width(1)))?;
    }
    Ok(())
}

/// A spring as a zigzag from `a` to `b` (pixels).
fn draw_zigzag(area: &Area<'_>, a: (i32, i32), b: (i32, i32), colour: RGBColor) -> DrawResult {
    let (dx, dy) = (f64::from(b.0 - a.0), f64::from(b.1 - a.1));
    let l = (dx * dx + dy * dy).sqrt().max(1.0);
    let (ux, uy) = (dx / l, dy / l);
    let (nx, ny) = (-uy, ux);
    let mut pts = vec![a];
    let teeth = 6;
    for k in 1..teeth {
        let t = 0.15 + 0.7 * f64::from(k) / f64::from(teeth);
        let side = if k % 2 == 0 { 5.0 } else { -5.0 };
        pts.push(((f64::from(a.0) + ux * l * t + nx * side) as i32, (f64::from(a.1) + uy * l * t + ny * side) as i32));
    }
    pts.push(b);
    area.draw(&PathElement::new(pts, colour.stroke_width(2)))?;
    Ok(())
}

/// An arrow from `a` to `b` (pixels) with its head at `b`.
fn draw_arrow(area: &Area<'_>, a: (i32, i32), b: (i32, i32), colour: RGBColor, width: u32) -> DrawResult {
    area.draw(&PathElement::new(vec![a, b], colour.stroke_width(width)))?;
    let (dx, dy) = (f64::from(b.0 - a.0), f64::from(b.1 - a.1));
    let l = (dx * dx + dy * dy).sqrt().max(1.0);
    let (ux, uy) = (dx / l, dy / l);
    let head = 7.0;
    let left =
        ((f64::from(b.0) - head * ux - 0.5 * head * uy) as i32, (f64::from(b.1) - head * uy + 0.5 * head * ux) as i32);
    let right =
        ((f64::from(b.0) - head * ux + 0.5 * head * uy) as i32, (f64::from(b.1) - head * uy - 0.5 * head * ux) as i32);
    area.draw(&Polygon::new(vec![b, left, right], colour.filled()))?;
    Ok(())
}

/// Pixel direction of a translation DOF, `None` for a rotation.
fn dof_dir(d: Dof) -> Option<(f64, f64)> {
    match d {
        Dof::Ux => Some((1.0, 0.0)),
        Dof::Uy => Some((0.0, -1.0)),
        Dof::Uz => {
            let l = RECEDING.0.hypot(RECEDING.1);
            Some((RECEDING.0 / l, -RECEDING.1 / l))
        }
        Dof::Rx | Dof::Ry | Dof::Rz => None,
    }
}

/// The measured DOFs: responses and excitations.
pub(crate) struct Sensors<'a> {
    /// Measured responses.
    pub(crate) responses: &'a [DofRef],
    /// Excitations (references).
    pub(crate) references: &'a [DofRef],
}

/// What a highlighted place is, which decides how it is marked.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum HighlightKind {
    /// A joint at a node: a ring.
    Joint,
    /// A support at a node: a ring.
    Support,
    /// A mass at a node: a filled square in a ring.
    Mass,
    /// A change over elements: a broad band along them.
    Patch,
    /// A resonator at a node (a mass on a spring): a ring around its mass.
    Resonator,
}

/// A place on the structure to point at, numbered in the figure.
pub(crate) struct Highlight {
    /// Legend text (the number is added in front).
    pub(crate) label: String,
    /// How to mark it.
    pub(crate) kind: HighlightKind,
    /// Node ids where it acts.
    pub(crate) nodes: Vec<u32>,
    /// Element ids where it acts.
    pub(crate) elements: Vec<u32>,
    /// Its number on the drawing and in the legend (`None`: its place in
    /// the list, from 1): the step that added it, or its rank.
    pub(crate) number: Option<usize>,
}

/// How far from its node a resonator's mass is drawn (pixels).
const RESONATOR_OFFSET: f64 = 32.0;

/// A resonator as a case's `[[resonators]]` builds it: a mass on a node of
/// its own, coincident with a node of the structure, joined to it by one
/// spring and nothing else (its other DOFs held). Drawn as a mass on a
/// spring beside the node, not as a joint and a support where it sits.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Resonator {
    /// The structure's node it hangs on.
    base: NodeId,
    /// The mass's own node.
    node: NodeId,
    /// Its spring's index in `Model::springs`.
    spring: usize,
    /// Pixel direction from the base to the mass: the spring's first
    /// translation (up for a vertical spring).
    dir: (f64, f64),
}

/// The resonators of `model` (see [`Resonator`]).
fn resonators(model: &Model) -> Vec<Resonator> {
    let dim = model.dimension();
    let mut out = Vec::new();
    for m in model.masses() {
        let n = m.node;
        if model.beams().iter().any(|b| b.nodes.contains(&n)) {
            continue;
        }
        let touching: Vec<usize> =
            model.springs().iter().enumerate().filter(|(_, s)| s.a == n || s.b == Some(n)).map(|(i, _)| i).collect();
        let [i] = touching[..] else { continue };
        let s = &model.springs()[i];
        let Some(other) = (if s.a == n { s.b } else { Some(s.a) }) else { continue };
        let (Some(p), Some(q)) = (node_xy(model, n), node_xy(model, other)) else { continue };
        if (p.0 - q.0).abs() + (p.1 - q.1).abs() > 1e-9 * (1.0 + p.0.abs() + p.1.abs()) {
            continue;
        }
        let Some(dir) = dim.translations().iter().find(|&&d| s.k[d] != 0.0).and_then(|&d| dof_dir(d)) else {
            continue;
        };
        out.push(Resonator { base: other, node: n, spring: i, dir });
    }
    out
}

/// A mass on a spring from `p` along `dir` (pixels); returns where the
/// mass is.
fn draw_resonator(
    area: &Area<'_>,
    p: (i32, i32),
    dir: (f64, f64),
    colour: RGBColor,
) -> Result<(i32, i32), Box<dyn std::error::Error>> {
    let end = add(p, dir, RESONATOR_OFFSET);
    draw_zigzag(area, p, add(p, dir, RESONATOR_OFFSET - 6.0), colour)?;
    area.draw(&Rectangle::new([(end.0 - 6, end.1 - 6), (end.0 + 6, end.1 + 6)], colour.filled()))?;
    Ok(end)
}

/// Draws the beams, supports, springs, masses and resonators of `model` in `view`.
fn draw_model(area: &Area<'_>, model: &Model, view: &View, colour: RGBColor, width: u32, symbols: bool) -> DrawResult {
    let at = |id: NodeId| node_xy(model, id).map(|(x, y)| view.px(x, y));
    let resonators = resonators(model);
    for b in model.beams() {
        if let (Some(p), Some(q)) = (at(b.nodes[0]), at(b.nodes[1])) {
            area.draw(&PathElement::new(vec![p, q], colour.stroke_width(width)))?;
        }
    }
    // an imported model has no elements to draw: a thin line joins each
    // pair of nodes its stiffness couples
    for [a, b] in imported_edges(model) {
        if let (Some(p), Some(q)) = (at(a), at(b)) {
            area.draw(&PathElement::new(vec![p, q], colour.stroke_width(1)))?;
        }
    }
    if !symbols {
        return Ok(());
    }
    for s in model.supports() {
        // a resonator's mass is held in the DOFs its spring leaves free, a
        // shaker's armature (`[[shakers]]`: a mass on a node of its own,
        // tied to the drive point) in those its stinger does not drive:
        // neither is a support of the structure
        let bare_mass =
            !model.beams().iter().any(|b| b.nodes.contains(&s.node)) && model.masses().iter().any(|m| m.node == s.node);
        if resonators.iter().any(|r| r.node == s.node) || bare_mass {
            continue;
        }
        let Some(p) = at(s.node) else { continue };
        let away = pixel_dir(beam_direction(model, s.node));
        let away = (-away.0, -away.1);
        if s.dofs.len() == model.node_dofs().len() {
            // clamped: a wall across the beam
            draw_ground(area, p, away, 14.0)?;
        } else {
            // pinned or sliding: a triangle on a ground
            let base = add(p, away, 14.0);
            let across = (-away.1, away.0);
            let tri = vec![p, add(base, across, 8.0), add(base, across, -8.0)];
            area.draw(&Polygon::new(tri.clone(), WHITE.filled()))?;
            area.draw(&PathElement::new(vec![tri[0], tri[1], tri[2], tri[0]], BEAM.stroke_width(2)))?;
            draw_ground(area, add(base, away, 2.0), away, 12.0)?;
        }
    }
    for (i, s) in model.springs().iter().enumerate() {
        if resonators.iter().any(|r| r.spring == i) {
            continue;
        }
        let Some(p) = at(s.a) else { continue };
        match s.b.and_then(at) {
            // coincident nodes: a joint, drawn as a hinge
            Some(q) if (q.0 - p.0).abs() + (q.1 - p.1).abs() <= 2 => {
                area.draw(&Circle::new(p, 6, WHITE.filled()))?;
                area.draw(&Circle::new(p, 6, BEAM.stroke_width(2)))?;
            }
            Some(q) => draw_zigzag(area, p, q, BEAM)?,
            None => {
                // a spring to ground, away from the structure
                let away = pixel_dir(beam_direction(model, s.a));
                let away = (-away.0, -away.1);
                let end = add(p, away, 30.0);
                draw_zigzag(area, p, end, BEAM)?;
                draw_ground(area, end, away, 12.0)?;
            }
        }
    }
    for m in model.masses() {
        if resonators.iter().any(|r| r.node == m.node) {
            continue;
        }
        if let Some(p) = at(m.node) {
            area.draw(&Rectangle::new([(p.0 - 6, p.1 - 6), (p.0 + 6, p.1 + 6)], BEAM.filled()))?;
        }
    }
    for r in &resonators {
        if let Some(p) = at(r.base) {
            draw_resonator(area, p, r.dir, BEAM)?;
        }
    }
    Ok(())
}

/// A numbered badge: a filled circle with white digits.
fn draw_badge(area: &Area<'_>, p: (i32, i32), number: usize, colour: RGBColor) -> DrawResult {
    area.draw(&Circle::new(p, 10, colour.filled()))?;
    let style = (FONT, 13).into_font().style(FontStyle::Bold).color(&WHITE).pos(Pos::new(HPos::Center, VPos::Center));
    area.draw(&Text::new(format!("{number}"), p, style))?;
    Ok(())
}

/// Height of the drawing for a structure of the given aspect in a figure
/// `WIDTH` wide.
fn drawing_height(aspect: f64) -> u32 {
    (aspect * f64::from(WIDTH - 160)).clamp(160.0, 440.0) as u32 + 80
}

/// The structure with its measured DOFs and highlighted places.
pub(crate) fn structure(
    title: &str,
    model: &Model,
    sensors: &Sensors<'_>,
    highlights: &[Highlight],
) -> Result<String, PlotError> {
    let mut legend = Vec::new();
    if !sensors.responses.is_empty() {
        legend.push(LegendEntry::new("measured response (arrow: direction)", RESPONSE, Mark::Line(2)));
    }
    if !sensors.references.is_empty() {
        legend.push(LegendEntry::new("excitation", EXCITATION, Mark::Line(3)));
    }
    for (i, h) in highlights.iter().enumerate() {
        let n = h.number.unwrap_or(i + 1);
        legend.push(LegendEntry::new(format!("{n}: {}", h.label), HIGHLIGHTS[i % HIGHLIGHTS.len()], Mark::Dot));
    }
    let height = drawing_height(aspect(model)) + 40 + super::legend_height(&legend);
    svg(title, height, |root| {
        let body = frame(root, title, &legend)?;
        let (w, h) = body.dim_in_pixel();
        let view = View::fit(bbox(model), f64::from(w), f64::from(h), 56.0);
        let at = |id: u32| node_xy(model, NodeId(id)).map(|(x, y)| view.px(x, y));
        let resonators = resonators(model);
        // patches under the beams, so that the beams stay visible on them
        for (i, h) in highlights.iter().enumerate() {
            if h.kind != HighlightKind::Patch {
                continue;
            }
            let colour = HIGHLIGHTS[i % HIGHLIGHTS.len()];
            for e in &h.elements {
                let Some(b) = model.beams().iter().find(|b| b.id.0 == *e) else { continue };
                if let (Some(p), Some(q)) = (at(b.nodes[0].0), at(b.nodes[1].0)) {
                    body.draw(&PathElement::new(vec![p, q], colour.mix(0.45).stroke_width(12)))?;
                }
            }
        }
        draw_model(&body, model, &view, BEAM, 3, true)?;
        for n in model.nodes() {
            if model.nodes().len() <= 200 {
                let (x, y) = project(model, n.position());
                body.draw(&Circle::new(view.px(x, y), 2, BEAM.filled()))?;
            }
        }
        // excitations point into the node, responses out of it
        for r in sensors.references {
            let (Some(p), Some(d)) = (at(r.node.0), dof_dir(r.dof)) else { continue };
            draw_arrow(&body, add(p, d, -34.0), add(p, d, -5.0), EXCITATION, 3)?;
        }
        for r in sensors.responses {
            let Some(p) = at(r.node.0) else { continue };
            match dof_dir(r.dof) {
                Some(d) => draw_arrow(&body, add(p, d, 4.0), add(p, d, 26.0), RESPONSE, 2)?,
                None => body.draw(&Circle::new(p, 10, RESPONSE.stroke_width(2)))?,
            }
        }
        // node numbers where something is measured, supported or highlighted
        let mut labelled: Vec<(i32, i32)> = Vec::new();
        let mut ids: Vec<u32> = sensors.responses.iter().chain(sensors.references).map(|r| r.node.0).collect();
        ids.extend(model.supports().iter().map(|s| s.node.0));
        ids.extend(highlights.iter().flat_map(|h| h.nodes.iter().copied()));
        ids.sort_unstable();
        ids.dedup();
        let style = (FONT, 12).into_font().color(&AXIS);
        for id in ids {
            let Some(p) = at(id) else { continue };
            if labelled.iter().any(|q| (q.0 - p.0).abs() + (q.1 - p.1).abs() <= 2) {
                continue;
            }
            labelled.push(p);
            // below and to the left, clear of a highlight's ring
            body.draw(&Text::new(format!("{id}"), (p.0 - 24, p.1 + 10), style.clone()))?;
        }
        for (i, h) in highlights.iter().enumerate() {
            let colour = HIGHLIGHTS[i % HIGHLIGHTS.len()];
            let points: Vec<(i32, i32)> = match h.kind {
                HighlightKind::Patch => h
                    .elements
                    .iter()
                    .filter_map(|e| model.beams().iter().find(|b| b.id.0 == *e))
                    .filter_map(|b| Some((at(b.nodes[0].0)?, at(b.nodes[1].0)?)))
                    .map(|(p, q)| ((p.0 + q.0) / 2, (p.1 + q.1) / 2))
                    .collect(),
                // the mass of the model's resonator at the node, or one
                // drawn there in the highlight's colour (a candidate the
                // model does not hold yet)
                HighlightKind::Resonator => {
                    let mut points = Vec::new();
                    for &n in &h.nodes {
                        let Some(p) = at(n) else { continue };
                        points.push(match resonators.iter().find(|r| r.base.0 == n || r.node.0 == n) {
                            Some(r) => add(p, r.dir, RESONATOR_OFFSET),
                            None => draw_resonator(&body, p, (0.0, -1.0), colour)?,
                        });
                    }
                    points
                }
                _ => h.nodes.iter().filter_map(|&n| at(n)).collect(),
            };
            let Some(&first) = points.first() else { continue };
            if h.kind != HighlightKind::Patch {
                for &p in &points {
                    if h.kind == HighlightKind::Mass {
                        body.draw(&Rectangle::new([(p.0 - 7, p.1 - 7), (p.0 + 7, p.1 + 7)], colour.filled()))?;
                    }
                    body.draw(&Circle::new(p, 15, colour.stroke_width(3)))?;
                }
            }
            let centre = if h.kind == HighlightKind::Patch {
                let n = points.len() as i32;
                (points.iter().map(|p| p.0).sum::<i32>() / n, points.iter().map(|p| p.1).sum::<i32>() / n)
            } else {
                first
            };
            draw_badge(&body, (centre.0 + 22, centre.1 - 22), h.number.unwrap_or(i + 1), colour)?;
        }
        Ok(())
    })
}

/// One mode of [`mode_shapes`]: the model's real displacement per node and
/// the measured one at the measured DOFs, on a common scale.
pub(crate) struct ShapePanel {
    /// Panel title.
    pub(crate) title: String,
    /// A line under the title.
    pub(crate) subtitle: String,
    /// The model's displacement per DOF per node id (absent nodes do not move).
    pub(crate) model: HashMap<u32, PerDof>,
    /// The measured displacement at each measured DOF.
    pub(crate) measured: Vec<(DofRef, f64)>,
}

/// Points along a beam deformed by end displacements `(ux, uy, rz)` times
/// `amp`: axial displacement linear, transverse cubic (Hermite, with the
/// end rotations), as the element's own shape functions.
fn deformed_beam(p: (f64, f64), q: (f64, f64), up: [f64; 3], uq: [f64; 3], amp: f64) -> Vec<(f64, f64)> {
    let (dx, dy) = (q.0 - p.0, q.1 - p.1);
    let l = (dx * dx + dy * dy).sqrt();
    if l <= 0.0 {
        return vec![(p.0 + amp * up[0], p.1 + amp * up[1])];
    }
    let (c, s) = (dx / l, dy / l);
    let axial = |u: [f64; 3]| c * u[0] + s * u[1];
    let trans = |u: [f64; 3]| -s * u[0] + c * u[1];
    let (a1, a2, v1, v2) = (axial(up), axial(uq), trans(up), trans(uq));
    let (r1, r2) = (up[2], uq[2]);
    (0..=16)
        .map(|k| {
            let t = f64::from(k) / 16.0;
            let u = a1 * (1.0 - t) + a2 * t;
            let v = (1.0 - 3.0 * t * t + 2.0 * t.powi(3)) * v1
                + (t - 2.0 * t * t + t.powi(3)) * l * r1
                + (3.0 * t * t - 2.0 * t.powi(3)) * v2
                + (t.powi(3) - t * t) * l * r2;
            (p.0 + t * dx + amp * (c * u - s * v), p.1 + t * dy + amp * (s * u + c * v))
        })
        .collect()
}

/// The amplitude factor that makes the largest translation of any panel a
/// sixth of the structure's size.
fn amplitude(model: &Model, panels: &[ShapePanel]) -> f64 {
    let (xmin, ymin, xmax, ymax) = bbox(model);
    let size = (xmax - xmin).max(ymax - ymin);
    let translation = |u: &PerDof| u[Dof::Ux].hypot(u[Dof::Uy]).hypot(u[Dof::Uz]);
    let largest = panels
        .iter()
        .flat_map(|p| p.model.values().map(translation).chain(p.measured.iter().map(|(_, v)| v.abs())))
        .filter(|v| v.is_finite())
        .fold(0.0f64, f64::max);
    if largest > 0.0 { size / 6.0 / largest } else { 0.0 }
}

/// Mode shapes on the structure, one panel per mode: the undeformed
/// structure in grey, the model's shape as a blue line, the measured
/// displacements as black dots.
pub(crate) fn mode_shapes(title: &str, model: &Model, panels: &[ShapePanel]) -> Result<String, PlotError> {
    let legend = vec![
        LegendEntry::new("undeformed", UNDEFORMED, Mark::Line(2)),
        LegendEntry::new("model", UPDATED, Mark::Line(2)),
        LegendEntry::new("measured (in its direction; the model's in the others)", MEASURED, Mark::Dot),
    ];
    let aspect = aspect(model);
    // a compact structure fits four to a row, a long one two
    let columns = match (panels.len(), aspect > 0.6) {
        (n, true) if n <= 4 => n.max(1),
        (_, true) => 3,
        (n, false) => n.clamp(1, 2),
    };
    let rows = panels.len().div_ceil(columns).max(1);
    let panel_w = f64::from(WIDTH) / columns as f64;
    let panel_h = (aspect * panel_w * 0.9).clamp(150.0, 420.0) + 76.0;
    let height = 44 + super::legend_height(&legend) + (rows as f64 * panel_h) as u32;
    let amp = amplitude(model, panels);
    // one view for every panel, so that their amplitudes compare
    let (xmin, ymin, xmax, ymax) = bbox(model);
    let pad = (xmax - xmin).max(ymax - ymin) / 6.0;
    let bbox = (xmin - pad, ymin - pad, xmax + pad, ymax + pad);
    svg(title, height, |root| {
        let body = frame(root, title, &legend)?;
        let cells = body.split_evenly((rows, columns));
        for (panel, cell) in panels.iter().zip(&cells) {
            cell.draw(&Text::new(
                panel.title.clone(),
                (10, 4),
                (FONT, 13).into_font().style(FontStyle::Bold).color(&BLACK),
            ))?;
            cell.draw(&Text::new(panel.subtitle.clone(), (10, 21), (FONT, 12).into_font().color(&AXIS)))?;
            let (_, area) = cell.split_vertically(38);
            let (w, h) = area.dim_in_pixel();
            let view = View::fit(bbox, f64::from(w), f64::from(h), 10.0);
            draw_model(&area, model, &view, UNDEFORMED, 2, false)?;
            let disp = |id: NodeId| panel.model.get(&id.0).copied().unwrap_or_default();
            for (i, b) in model.beams().iter().enumerate() {
                let pts: Vec<(i32, i32)> = match model.dimension() {
                    Dimension::Planar => {
                        let (Some(p), Some(q)) = (node_xy(model, b.nodes[0]), node_xy(model, b.nodes[1])) else {
                            continue;
                        };
                        let planar = |u: PerDof| [u[Dof::Ux], u[Dof::Uy], u[Dof::Rz]];
                        deformed_beam(p, q, planar(disp(b.nodes[0])), planar(disp(b.nodes[1])), amp)
                            .into_iter()
                            .map(|(x, y)| view.px(x, y))
                            .collect()
                    }
                    Dimension::Spatial => {
                        let [p, q] = b.nodes.map(|n| model.node(n).map(|n| n.position()).unwrap_or_default());
                        deformed_beam_3d(p, q, &model.beam_axes(i), disp(b.nodes[0]), disp(b.nodes[1]), amp)
                            .into_iter()
                            .map(|at| {
                                let (x, y) = project(model, at);
                                view.px(x, y)
                            })
                            .collect()
                    }
                };
                area.draw(&PathElement::new(pts, UPDATED.stroke_width(2)))?;
            }
            // an imported model's node pairs, straight between the displaced nodes
            for [p, q] in imported_edges(model) {
                let moved = |id: NodeId| {
                    let (n, u) = (model.node(id)?, disp(id));
                    let [x, y, z] = n.position();
                    let (x, y) = project(model, [x + amp * u[Dof::Ux], y + amp * u[Dof::Uy], z + amp * u[Dof::Uz]]);
                    Some(view.px(x, y))
                };
                if let (Some(a), Some(b)) = (moved(p), moved(q)) {
                    area.draw(&PathElement::new(vec![a, b], UPDATED.stroke_width(1)))?;
                }
            }
            // a measured value moves its node in the measured direction, the
            // model's displacement in the others: where the shapes agree, the
            // dot sits on the blue line
            for (d, v) in &panel.measured {
                let Some(node) = model.node(d.node) else { continue };
                if !d.dof.is_translation() {
                    continue;
                }
                let mut u = disp(d.node);
                u[d.dof] = *v;
                let [x, y, z] = node.position();
                let (x, y) = project(model, [x + amp * u[Dof::Ux], y + amp * u[Dof::Uy], z + amp * u[Dof::Uz]]);
                area.draw(&Circle::new(view.px(x, y), 4, MEASURED.filled()))?;
            }
        }
        Ok(())
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn l_frame() -> Model {
        let mut m = Model::new("L");
        let steel = m.add_material("steel", 2.1e11, 7850.0).unwrap();
        let sec = m.add_section(fe_model::Section::rectangle("sq", 0.02, 0.02)).unwrap();
        let g = m.group_or_default("frame");
        m.add_node(1, 0.0, 0.0).unwrap();
        m.add_node(2, 0.0, 0.6).unwrap();
        m.add_node(3, 0.5, 0.6).unwrap();
        m.add_beam(1, [1, 2], steel, sec, g).unwrap();
        m.add_beam(2, [2, 3], steel, sec, g).unwrap();
        m.add_support(1, &Dof::PLANAR).unwrap();
        m
    }

    #[test]
    fn the_view_keeps_the_scale_equal_and_the_structure_inside() {
        let v = View::fit((0.0, 0.0, 0.5, 0.6), 800.0, 400.0, 20.0);
        let (a, b) = (v.px(0.0, 0.0), v.px(0.5, 0.6));
        // the height limits: 360 px for 0.6 m
        assert_eq!(a.1 - b.1, 360);
        assert_eq!(b.0 - a.0, 300);
        assert!(a.0 >= 20 && b.0 <= 780 && b.1 >= 20 && a.1 <= 380);
    }

    #[test]
    fn a_rigid_rotation_deforms_a_beam_into_a_straight_line() {
        // a small rotation theta about the first node: uy = theta x, rz = theta
        let theta = 0.01;
        let pts = deformed_beam((0.0, 0.0), (1.0, 0.0), [0.0, 0.0, theta], [0.0, theta, theta], 1.0);
        for (x, y) in pts {
            assert!((y - theta * x).abs() < 1e-12, "({x}, {y})");
        }
        // and a cantilever's tip load shape is cubic, not a polygon
        let pts = deformed_beam((0.0, 0.0), (1.0, 0.0), [0.0; 3], [0.0, 1.0, 1.5], 1.0);
        let mid = pts[8];
        assert!((mid.1 - (3.0 * 0.25 - 2.0 * 0.125 + (0.125 - 0.25) * 1.5)).abs() < 1e-12, "{mid:?}");
    }

    #[test]
    fn the_structure_figure_marks_sensors_and_numbered_highlights() {
        let m = l_frame();
        let responses = [DofRef::new(3, Dof::Uy), DofRef::new(2, Dof::Ux)];
        let references = [DofRef::new(3, Dof::Uy)];
        let highlights = vec![
            Highlight {
                label: "a joint".into(),
                kind: HighlightKind::Joint,
                nodes: vec![2],
                elements: vec![2],
                number: None,
            },
            Highlight {
                label: "a patch".into(),
                kind: HighlightKind::Patch,
                nodes: vec![],
                elements: vec![1],
                number: None,
            },
        ];
        let svg =
            structure("frame", &m, &Sensors { responses: &responses, references: &references }, &highlights).unwrap();
        for text in ["1: a joint", "2: a patch", "measured response (arrow: direction)", "excitation", "1", "2", "3"] {
            assert!(super::super::has_text(&svg, text), "missing {text}");
        }
        // two beams, a ring for the joint in the first highlight colour
        let ring = format!("stroke=\"#{:02X}{:02X}{:02X}\"", HIGHLIGHTS[0].0, HIGHLIGHTS[0].1, HIGHLIGHTS[0].2);
        assert!(svg.contains("<circle") && svg.contains(&ring), "{ring}");
    }

    #[test]
    fn every_kind_of_effect_is_marked_in_a_colour_of_its_own() {
        let m = l_frame();
        let kinds = [
            ("a joint", HighlightKind::Joint, vec![2], vec![2]),
            ("a support", HighlightKind::Support, vec![1], vec![]),
            ("a mass", HighlightKind::Mass, vec![3], vec![]),
            ("a patch", HighlightKind::Patch, vec![], vec![1]),
        ];
        let highlights: Vec<Highlight> = kinds
            .iter()
            .map(|(label, kind, nodes, elements)| Highlight {
                label: (*label).into(),
                kind: *kind,
                nodes: nodes.clone(),
                elements: elements.clone(),
                number: None,
            })
            .collect();
        let svg = structure("frame", &m, &Sensors { responses: &[], references: &[] }, &highlights).unwrap();
        let hex = |c: RGBColor| format!("#{:02X}{:02X}{:02X}", c.0, c.1, c.2);
        let distinct: std::collections::HashSet<String> = HIGHLIGHTS.iter().map(|&c| hex(c)).collect();
        assert_eq!(distinct.len(), HIGHLIGHTS.len());
        for (i, (label, ..)) in kinds.iter().enumerate() {
            assert!(super::super::has_text(&svg, &format!("{}: {label}", i + 1)), "legend of {label}");
            // its mark on the drawing and its dot in the legend
            assert!(svg.matches(&hex(HIGHLIGHTS[i])).count() >= 2, "{label} is not drawn in {}", hex(HIGHLIGHTS[i]));
        }
        // the mass is a filled square in its colour
        assert!(
            svg.lines().any(|l| l.starts_with("<rect") && l.contains(&format!("fill=\"{}\"", hex(HIGHLIGHTS[2])))),
            "no square for the mass"
        );
    }

    /// The L-frame with a resonator at its tip as `[[resonators]]` builds
    /// one: a coincident node, a vertical spring, a mass, the rest held.
    fn l_frame_with_resonator() -> Model {
        let mut m = l_frame();
        let g = m.group_or_default("frame");
        m.add_node(4, 0.5, 0.6).unwrap();
        m.add_spring("fixture", 3, Some(4), [0.0, 2e4, 0.0], g).unwrap();
        m.add_mass("fixture", 4, 0.3, [0.0; 3], g).unwrap();
        m.add_support(4, &[Dof::Ux, Dof::Rz]).unwrap();
        m
    }

    /// A resonator is found as built, and drawn as a mass on a spring
    /// beside its node: a zigzag up from the tip and a square at its end,
    /// neither the hinge of a joint nor the triangle of a support at the
    /// tip; its highlight rings the drawn mass.
    #[test]
    fn a_resonator_is_drawn_as_a_mass_on_a_spring_beside_its_node() {
        let plain = l_frame();
        let m = l_frame_with_resonator();
        assert!(resonators(&plain).is_empty());
        let r = resonators(&m);
        assert_eq!(r, [Resonator { base: NodeId(3), node: NodeId(4), spring: 0, dir: (0.0, -1.0) }]);
        // a joint between coincident nodes of two beams is not a resonator
        let mut joint = l_frame();
        let g = joint.group_or_default("frame");
        joint.add_node(5, 0.5, 0.6).unwrap();
        joint.add_node(6, 1.0, 0.6).unwrap();
        let (steel, sec) = (0, 0);
        joint.add_beam(3, [5, 6], steel, sec, g).unwrap();
        joint.add_spring("hinge", 3, Some(5), [1e9, 1e9, 1e3], g).unwrap();
        assert!(resonators(&joint).is_empty());

        let highlight =
            |kind| Highlight { label: "a resonator".into(), kind, nodes: vec![3], elements: vec![], number: None };
        let no_sensors = Sensors { responses: &[], references: &[] };
        let without = structure("frame", &plain, &no_sensors, &[]).unwrap();
        let with = structure("frame", &m, &no_sensors, &[highlight(HighlightKind::Resonator)]).unwrap();
        let count = |svg: &str, what: &str| svg.lines().filter(|l| l.starts_with(what)).count();
        // a square for the mass and no hinge ring, no support triangle
        assert_eq!(count(&with, "<rect") - count(&without, "<rect"), 1, "one square: the mass");
        assert_eq!(count(&with, "<polygon"), count(&without, "<polygon"), "a support drawn at the resonator");
        let ring = format!("stroke=\"#{:02X}{:02X}{:02X}\"", HIGHLIGHTS[0].0, HIGHLIGHTS[0].1, HIGHLIGHTS[0].2);
        assert!(
            with.lines().any(|l| l.starts_with("<circle") && l.contains("r=\"15\"") && l.contains(&ring)),
            "no ring in the highlight's colour"
        );
        // a candidate the model does not hold yet is drawn in its colour
        let candidate = structure("frame", &plain, &no_sensors, &[highlight(HighlightKind::Resonator)]).unwrap();
        let fill = format!("fill=\"#{:02X}{:02X}{:02X}\"", HIGHLIGHTS[0].0, HIGHLIGHTS[0].1, HIGHLIGHTS[0].2);
        assert!(candidate.lines().any(|l| l.starts_with("<rect") && l.contains(&fill)), "no mass for the candidate");
    }

    /// A shaker (`[[shakers]]`: the armature's mass on a node of its own,
    /// tied to the drive point, held in its other DOFs, on a spring to
    /// ground) is drawn as a mass and a spring to ground at the drive
    /// point, not as a support of the structure there.
    #[test]
    fn a_shaker_is_drawn_as_a_mass_on_a_spring_to_ground_not_a_support() {
        let plain = l_frame();
        let mut m = l_frame();
        let g = m.group_or_default("frame");
        m.add_node(4, 0.5, 0.6).unwrap();
        m.add_tie(3, 4, &[Dof::Uy]).unwrap();
        m.add_support(4, &[Dof::Ux, Dof::Rz]).unwrap();
        m.add_mass("coil", 4, 0.05, [0.0; 3], g).unwrap();
        m.add_spring("coil", 4, None, [0.0, 3e3, 0.0], g).unwrap();
        assert!(resonators(&m).is_empty(), "no resonator: its spring goes to ground");
        let no_sensors = Sensors { responses: &[], references: &[] };
        let without = structure("frame", &plain, &no_sensors, &[]).unwrap();
        let with = structure("frame", &m, &no_sensors, &[]).unwrap();
        let count = |svg: &str, what: &str| svg.lines().filter(|l| l.starts_with(what)).count();
        assert_eq!(count(&with, "<rect") - count(&without, "<rect"), 1, "one square: the armature");
        assert_eq!(count(&with, "<polygon"), count(&without, "<polygon"), "a support drawn at the drive point");
        assert!(
            count(&with, "<polyline") + count(&with, "<path") > count(&without, "<polyline") + count(&without, "<path")
        );
    }

    #[test]
    fn mode_shapes_draw_one_panel_per_mode() {
        let m = l_frame();
        let panels: Vec<ShapePanel> = (1..=3)
            .map(|k| ShapePanel {
                title: format!("mode {k}"),
                subtitle: String::new(),
                model: [(2, [0.01 * f64::from(k), 0.0, 0.0].into()), (3, [0.01, 0.02, 0.0].into())]
                    .into_iter()
                    .collect(),
                measured: vec![(DofRef::new(3, Dof::Uy), 0.018)],
            })
            .collect();
        let svg = mode_shapes("shapes", &m, &panels).unwrap();
        for k in 1..=3 {
            assert!(super::super::has_text(&svg, &format!("mode {k}")));
        }
        // the measured dot of each panel
        assert_eq!(svg.matches("<circle").count(), 3 + 1, "three dots and the legend's");
        assert!(!svg.contains("<circle cx=\"0\""), "{svg}");
    }
}

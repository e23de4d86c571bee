//! Curves thinned to what can be drawn: at most four points per pixel
//! column, chosen so that the drawn line is the same.
//!
//! A measured FRF of 494,000 lines drawn 600 pixels wide puts some 800
//! points in every pixel column; written out in full, the curves of 10
//! channels made a report of 194 MB. Points of a polyline that fall in one pixel column all have the
//! same drawn x, so between entering and leaving the column the line only
//! runs up and down it: it covers, in that column, the span from its
//! highest to its lowest point. Keeping the first point of each column (where
//! the line enters), the highest, the lowest and the last (where it leaves),
//! in their order along the curve, draws the same pixels: every peak and
//! every notch is at its exact height, and nothing between columns changes.
//! Likewise a shaded span narrower than a pixel is drawn zero pixels wide
//! and can be left out.

/// The points of `points` that draw the same polyline: of each run of
/// consecutive points in one pixel column, the first, the highest, the
/// lowest and the last, in their order. `pixel` maps a point to its drawn
/// (backend) coordinates, as the chart that draws it does
/// (`ChartContext::backend_coord`). A curve with at most one point per
/// column comes back unchanged.
pub(super) fn per_pixel_column<P: Copy>(points: &[P], pixel: impl Fn(&P) -> (i32, i32)) -> Vec<P> {
    let drawn: Vec<(i32, i32)> = points.iter().map(&pixel).collect();
    let mut out = Vec::with_capacity(points.len().min(4 * 4096));
    let mut start = 0;
    while start < points.len() {
        let column = drawn[start].0;
        let (mut top, mut bottom) = (start, start);
        let mut end = start + 1;
        while end < points.len() && drawn[end].0 == column {
            // backend y grows downwards: the highest point has the least y
            if drawn[end].1 < drawn[top].1 {
                top = end;
            }
            if drawn[end].1 > drawn[bottom].1 {
                bottom = end;
            }
            end += 1;
        }
        let mut keep = [start, top, bottom, end - 1];
        keep.sort_unstable();
        let mut last = None;
        for k in keep {
            if last != Some(k) {
                out.push(points[k]);
                last = Some(k);
            }
        }
        start = end;
    }
    out
}

/// Shaded spans `(from, to, level)` of the x axis, in order and not
/// overlapping, as they are drawn: a span that starts and ends in one
/// pixel column is drawn zero pixels wide and is left out. What remains is
/// at least a pixel wide each, so there are no more than pixel columns.
/// `column` maps an x to its drawn (backend) x.
pub(super) fn spans_per_pixel(spans: &[(f64, f64, u8)], column: impl Fn(f64) -> i32) -> Vec<(f64, f64, u8)> {
    spans.iter().copied().filter(|&(a, b, _)| column(a) != column(b)).collect()
}

/// The points of the polylines of an SVG whose tag contains `with` (an
/// attribute, such as `stroke-width="3"`; "" for all), in order.
#[cfg(test)]
pub(super) fn polylines(svg: &str, with: &str) -> Vec<Vec<(i32, i32)>> {
    svg.split("<polyline")
        .skip(1)
        .filter(|p| p.split("/>").next().unwrap_or_default().contains(with))
        .map(|p| {
            let points = p.split("points=\"").nth(1).and_then(|r| r.split('"').next()).unwrap_or_default();
            points
                .split_whitespace()
                .map(|xy| {
                    let (x, y) = xy.split_once(',').unwrap();
                    (x.parse().unwrap(), y.parse().unwrap())
                })
                .collect()
        })
        .collect()
}

/// The most points any pixel column of a polyline holds.
#[cfg(test)]
pub(super) fn most_per_column(line: &[(i32, i32)]) -> usize {
    let mut per_column = std::collections::BTreeMap::new();
    for p in line {
        *per_column.entry(p.0).or_insert(0) += 1;
    }
    per_column.into_values().max().unwrap_or(0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use plotters::prelude::*;

    /// Per pixel column of a polyline: its drawn span (least and greatest y).
    fn spans(line: &[(i32, i32)]) -> std::collections::BTreeMap<i32, (i32, i32)> {
        let mut out = std::collections::BTreeMap::new();
        for &(x, y) in line {
            let s = out.entry(x).or_insert((y, y));
            *s = (s.0.min(y), s.1.max(y));
        }
        out
    }

    /// Draws `points` as plotters draws a figure's curve, thinned or not,
    /// and returns the polyline's drawn points.
    fn drawn(points: &[(f64, f64)], thin: bool) -> Vec<(i32, i32)> {
        let mut svg = String::new();
        {
            let root = SVGBackend::with_string(&mut svg, (640, 300)).into_drawing_area();
            let mut chart = ChartBuilder::on(&root)
                .margin(10)
                .y_label_area_size(50)
                .build_cartesian_2d(0.0..1.0, -80.0..80.0)
                .unwrap();
            let points = if thin { per_pixel_column(points, |p| chart.backend_coord(p)) } else { points.to_vec() };
            chart.draw_series(LineSeries::new(points, BLACK.stroke_width(1))).unwrap();
            root.present().unwrap();
        }
        polylines(&svg, "").remove(0)
    }

    /// Two resonances in dB over `n` points of [0, 1], with a ripple at
    /// every point, as noise makes.
    fn curve(n: usize) -> Vec<(f64, f64)> {
        (0..n)
            .map(|k| {
                let x = k as f64 / (n - 1) as f64;
                let h = 1.0 / (1.0 - (x / 0.31).powi(2)).hypot(0.004 * x) - 0.6 / (1.0 - (x / 0.7).powi(2)).hypot(0.01);
                let ripple = if k % 2 == 0 { 0.3 } else { -0.3 };
                (x, 20.0 * h.abs().max(1e-3).log10() + ripple)
            })
            .collect()
    }

    #[test]
    fn a_million_points_draw_the_same_line_with_at_most_four_per_pixel_column() {
        let points = curve(1_000_000);
        let (full, thin) = (drawn(&points, false), drawn(&points, true));
        assert_eq!(full.len(), 1_000_000);
        let columns = spans(&full).len();
        assert!(thin.len() <= 4 * columns, "{} points for {columns} columns", thin.len());
        assert!(most_per_column(&thin) <= 4, "{} points in a column", most_per_column(&thin));
        // every column spans the same pixels: the highest peak, the deepest
        // notch and every ripple in between are drawn where they were
        assert_eq!(spans(&thin), spans(&full));
        let highest = |l: &[(i32, i32)]| l.iter().map(|p| p.1).min();
        assert_eq!(highest(&thin), highest(&full));
        assert_eq!((thin.first(), thin.last()), (full.first(), full.last()));
    }

    /// The level painted on each pixel column by `spans` drawn in order
    /// (a later span paints over an earlier one), as plotters draws a
    /// filled rectangle from its left column up to its right one.
    fn painted(spans: &[(f64, f64, u8)], column: impl Fn(f64) -> i32) -> std::collections::BTreeMap<i32, u8> {
        let mut out = std::collections::BTreeMap::new();
        for &(a, b, level) in spans {
            for x in column(a)..column(b) {
                out.insert(x, level);
            }
        }
        out
    }

    #[test]
    fn shaded_spans_at_every_line_paint_the_same_columns_with_at_most_one_span_per_column() {
        // a coherence that changes level at every one of 100,000 lines: fair,
        // below the threshold, poor, in a pattern of seven
        let column = |x: f64| (x * 600.0).round() as i32;
        let n = 100_000;
        let mut spans = Vec::new();
        for k in 0..n {
            let level = [0u8, 1, 2, 1, 1, 0, 2][k % 7];
            let (a, b) = (k as f64 / n as f64, (k + 1) as f64 / n as f64);
            match spans.last_mut() {
                Some((_, to, l)) if *l == level => *to = b,
                _ if level == 0 => {}
                _ => spans.push((a, b, level)),
            }
        }
        // and a few spans wider than a pixel
        let wide = [(0.2, 0.25, 1u8), (0.25, 0.3, 2), (0.3, 0.31, 1), (0.5, 0.6, 2)];
        let spans: Vec<(f64, f64, u8)> =
            spans.into_iter().filter(|s| wide.iter().all(|w| s.1 <= w.0 || s.0 >= w.1)).chain(wide).collect();
        let mut spans = spans;
        spans.sort_by(|a, b| a.0.total_cmp(&b.0));
        let thin = spans_per_pixel(&spans, column);
        assert!(spans.len() > 10_000 && thin.len() <= 600, "{} spans from {}", thin.len(), spans.len());
        assert_eq!(painted(&thin, column), painted(&spans, column));
        assert!(thin.iter().all(|s| column(s.0) < column(s.1)));
    }

    #[test]
    fn a_curve_with_fewer_points_than_pixel_columns_is_unchanged() {
        let points = curve(200);
        assert_eq!(drawn(&points, true), drawn(&points, false));
        let pixel = |p: &(f64, f64)| ((p.0 * 600.0) as i32, (p.1 * 10.0) as i32);
        assert_eq!(per_pixel_column(&points, pixel), points);
        assert!(per_pixel_column(&[] as &[(f64, f64)], pixel).is_empty());
    }
}

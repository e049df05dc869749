//! SVG scatter plots with logarithmic axes for the report's speed-against-error figure, drawn
//! by `plotters` (SVG backend): small multiples (one panel per scene, in rows), one colour
//! per series and a marker per precision, each panel's Pareto front joined, one legend below
//! them all.

use plotters::coord::Shift;
use plotters::prelude::*;

/// One point: position and an optional short label drawn beside it.
#[derive(Clone, Debug)]
pub struct Point {
    /// Horizontal value (> 0; log axis).
    pub x: f64,
    /// Vertical value; values at or below the axis floor are drawn on the floor line.
    pub y: f64,
    /// Label (empty: none).
    pub label: String,
}

/// How a series' points are drawn.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Marker {
    /// A filled circle.
    Circle,
    /// A filled square.
    Square,
}

/// Points drawn in one colour and marker.
#[derive(Clone, Debug)]
pub struct Series {
    /// Name (the legend's entries are given apart, [`svg`]).
    pub name: String,
    /// CSS colour.
    pub color: &'static str,
    /// Marker.
    pub marker: Marker,
    /// Whether its points take part in the panel's Pareto front (a reference, whose error is
    /// zero by definition, does not).
    pub on_front: bool,
    /// Points.
    pub points: Vec<Point>,
}

/// A panel: title, axis labels and the floor of the vertical axis (exact zeros, which a log
/// axis cannot show, are drawn on it and the axis says so).
#[derive(Clone, Debug)]
pub struct Panel {
    /// Title.
    pub title: String,
    /// Horizontal axis label.
    pub x_label: String,
    /// Vertical axis label.
    pub y_label: String,
    /// Smallest vertical value shown.
    pub y_floor: f64,
    /// Series.
    pub series: Vec<Series>,
    /// Whether to join the panel's Pareto front: of the series [`Series::on_front`], the
    /// points no other point beats on both axes at once (larger `x`, smaller `y`), in order
    /// of `x`.
    pub pareto: bool,
}

/// One entry of the legend below the panels.
#[derive(Clone, Debug)]
pub struct LegendEntry {
    /// Text.
    pub name: String,
    /// CSS colour.
    pub color: &'static str,
    /// Marker.
    pub marker: Marker,
}

/// The Pareto front's colour (dark grey: beside the series' colours, not one of them).
const FRONT: RGBColor = RGBColor(0x33, 0x33, 0x33);

/// Width and height of one panel, in pixels.
const PANEL: (u32, u32) = (400, 300);
/// Height of one legend row.
const LEGEND_ROW: u32 = 22;
/// Legend entries per row.
const LEGEND_COLUMNS: usize = 4;

/// Decades `[lo, hi]` covering the finite positive values (those at or below `floor` counted
/// as `floor`), at least one wide.
fn decades(values: impl Iterator<Item = f64>, floor: f64) -> (i32, i32) {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for v in values {
        let v = v.max(floor);
        if v.is_finite() && v > 0.0 {
            lo = lo.min(v);
            hi = hi.max(v);
        }
    }
    if !lo.is_finite() {
        return (0, 1);
    }
    let (a, b) = (lo.log10().floor() as i32, hi.log10().ceil() as i32);
    (a, b.max(a + 1))
}

/// A CSS colour `#rrggbb` as plotters' colour (black for anything else).
fn rgb(css: &str) -> RGBColor {
    let hex = css.strip_prefix('#').unwrap_or("");
    let byte = |i: usize| {
        hex.get(i..i + 2)
            .and_then(|h| u8::from_str_radix(h, 16).ok())
            .unwrap_or(0)
    };
    if hex.len() == 6 {
        RGBColor(byte(0), byte(2), byte(4))
    } else {
        match css {
            "red" => RED,
            "blue" => BLUE,
            "green" => GREEN,
            _ => BLACK,
        }
    }
}

/// The Pareto front of `points` (`x` to maximise, `y` to minimise, `y` below `floor` taken as
/// `floor`), in increasing `x`: a point is on it when every point with a larger `x` has a
/// larger `y`.
#[must_use]
pub fn pareto_front(points: &[(f64, f64)], floor: f64) -> Vec<(f64, f64)> {
    let mut sorted: Vec<(f64, f64)> = points
        .iter()
        .filter(|p| p.0 > 0.0 && p.0.is_finite() && !p.1.is_nan())
        .map(|&(x, y)| (x, y.max(floor)))
        .collect();
    sorted.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.1.total_cmp(&b.1)));
    let mut front = Vec::new();
    let mut best = f64::INFINITY;
    for p in sorted {
        if p.1 < best {
            best = p.1;
            front.push(p);
        }
    }
    front.reverse();
    front
}

/// Panels in rows of `columns` as one SVG document, `legend` below them.
#[must_use]
pub fn svg(panels: &[Panel], columns: usize, legend: &[LegendEntry]) -> String {
    let columns = columns.clamp(1, panels.len().max(1));
    let rows = panels.len().div_ceil(columns).max(1);
    let legend_h = LEGEND_ROW * legend.len().div_ceil(LEGEND_COLUMNS) as u32 + 10;
    let size = (PANEL.0 * columns as u32, PANEL.1 * rows as u32 + legend_h);
    let mut out = String::new();
    // Drawing into a String cannot fail for I/O; an error would mean a plotters bug, and the
    // report then carries a note instead of the figure.
    if let Err(e) = draw(&mut out, size, panels, (rows, columns), legend) {
        return format!(
            "<svg xmlns=\"http://www.w3.org/2000/svg\"><text y=\"20\">plot failed: {e}</text></svg>\n"
        );
    }
    out
}

/// A marker of `color` centred at `at` (pixels, in `area`).
fn marker_at(
    area: &DrawingArea<SVGBackend<'_>, Shift>,
    marker: Marker,
    at: (i32, i32),
    color: RGBColor,
) -> Result<(), Box<dyn std::error::Error>> {
    match marker {
        Marker::Circle => area.draw(&Circle::new(at, 5, color.filled()))?,
        Marker::Square => area.draw(&Rectangle::new(
            [(at.0 - 4, at.1 - 4), (at.0 + 4, at.1 + 4)],
            color.filled(),
        ))?,
    }
    Ok(())
}

fn draw(
    out: &mut String,
    size: (u32, u32),
    panels: &[Panel],
    grid: (usize, usize),
    legend: &[LegendEntry],
) -> Result<(), Box<dyn std::error::Error>> {
    let root = SVGBackend::with_string(out, size).into_drawing_area();
    root.fill(&WHITE)?;
    let (upper, lower) = root.split_vertically(PANEL.1 * grid.0 as u32);
    let areas = upper.split_evenly(grid);
    for (panel, area) in panels.iter().zip(&areas) {
        draw_panel(panel, area)?;
    }
    let column_width = (size.0 as usize / LEGEND_COLUMNS).max(1) as i32;
    for (k, entry) in legend.iter().enumerate() {
        let (x, y) = (
            20 + column_width * (k % LEGEND_COLUMNS) as i32,
            16 + LEGEND_ROW as i32 * (k / LEGEND_COLUMNS) as i32,
        );
        marker_at(&lower, entry.marker, (x, y), rgb(entry.color))?;
        lower.draw(&Text::new(
            entry.name.clone(),
            (x + 10, y - 6),
            ("sans-serif", 11),
        ))?;
    }
    root.present()?;
    Ok(())
}

fn draw_panel(
    panel: &Panel,
    area: &DrawingArea<SVGBackend<'_>, Shift>,
) -> Result<(), Box<dyn std::error::Error>> {
    let points = || panel.series.iter().flat_map(|s| s.points.iter());
    let (xa, xb) = decades(points().map(|p| p.x), 0.0);
    let (ya, yb) = decades(points().map(|p| p.y), panel.y_floor);
    let (x_range, y_range) = (
        10f64.powi(xa)..10f64.powi(xb),
        10f64.powi(ya)..10f64.powi(yb),
    );
    let mut chart = ChartBuilder::on(area)
        .caption(&panel.title, ("sans-serif", 13))
        .margin(12)
        .x_label_area_size(36)
        .y_label_area_size(56)
        .build_cartesian_2d(x_range.log_scale(), y_range.log_scale())?;
    let floor = panel.y_floor;
    chart
        .configure_mesh()
        .x_desc(&panel.x_label)
        // The bottom line also holds the exact zeros, which a log axis cannot show.
        .y_desc(format!("{} (<= {floor:.0e} at the bottom)", panel.y_label))
        .x_label_formatter(&|v| format!("{v:.0e}"))
        .y_label_formatter(&|v| format!("{v:.0e}"))
        .draw()?;
    if panel.pareto {
        let all: Vec<(f64, f64)> = panel
            .series
            .iter()
            .filter(|s| s.on_front)
            .flat_map(|s| s.points.iter().map(|p| (p.x, p.y)))
            .collect();
        let front = pareto_front(&all, floor);
        if front.len() > 1 {
            chart.draw_series(LineSeries::new(front, FRONT.stroke_width(2)))?;
        }
    }
    for s in &panel.series {
        let color = rgb(s.color).mix(0.85);
        let shown = s
            .points
            .iter()
            .filter(|p| p.x > 0.0 && p.x.is_finite() && !p.y.is_nan());
        for p in shown {
            let at = (p.x, p.y.max(floor));
            let label = Text::new(p.label.clone(), (7, -12), ("sans-serif", 9));
            match s.marker {
                Marker::Circle => chart.draw_series(std::iter::once(
                    EmptyElement::at(at) + Circle::new((0, 0), 5, color.filled()) + label,
                ))?,
                Marker::Square => chart.draw_series(std::iter::once(
                    EmptyElement::at(at)
                        + Rectangle::new([(-4, -4), (4, 4)], color.filled())
                        + label,
                ))?,
            };
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The centres of the circles drawn in `fill` (plotters writes `cx`, `cy` and `fill`
    /// attributes on one element).
    fn circles(doc: &str, fill: &str) -> Vec<(f64, f64)> {
        doc.split("<circle")
            .skip(1)
            .filter(|c| c.to_ascii_uppercase().contains(&format!("FILL=\"{fill}\"")))
            .map(|c| {
                let num = |key: &str| {
                    let s = &c[c.find(key).unwrap() + key.len()..];
                    s[..s.find('"').unwrap()].parse::<f64>().unwrap()
                };
                (num("cx=\""), num("cy=\""))
            })
            .collect()
    }

    #[test]
    fn points_land_inside_the_plot_and_zeros_on_the_floor() {
        let panel = Panel {
            title: "t".into(),
            x_label: "x".into(),
            y_label: "y".into(),
            y_floor: 1e-9,
            pareto: false,
            series: vec![Series {
                name: "a<b".into(),
                color: "#d62728",
                marker: Marker::Circle,
                on_front: true,
                points: vec![
                    Point {
                        x: 0.3,
                        y: 0.0,
                        label: "zero".into(),
                    },
                    Point {
                        x: 2.0,
                        y: 1e-3,
                        label: "p".into(),
                    },
                    Point {
                        x: f64::NAN,
                        y: 1.0,
                        label: "dropped".into(),
                    },
                ],
            }],
        };
        let legend = [LegendEntry {
            name: "a<b".into(),
            color: "#d62728",
            marker: Marker::Circle,
        }];
        let doc = svg(&[panel], 3, &legend);
        assert!(
            doc.starts_with("<svg") && doc.trim_end().ends_with("</svg>"),
            "{doc}"
        );
        assert!(doc.contains("a&lt;b") && !doc.contains("a<b"));
        assert!(!doc.contains("dropped") && !doc.contains("plot failed"));
        // Two points and one legend entry, all inside the figure.
        let drawn = circles(&doc, "#D62728");
        assert_eq!(drawn.len(), 3, "{doc}");
        let (w, h) = (f64::from(PANEL.0), f64::from(PANEL.1));
        for (x, y) in &drawn[..2] {
            assert!((0.0..w).contains(x) && (0.0..h).contains(y), "{x}, {y}");
        }
        // The zero sits on the floor, the lowest decade: below (larger y than) the other
        // point, and left of it (0.3 < 2).
        assert!(
            drawn[0].1 > drawn[1].1 && drawn[0].0 < drawn[1].0,
            "{drawn:?}"
        );
    }

    /// The front keeps the points no other beats on both axes, in increasing speed; zeros
    /// count as the floor; small multiples put a square per f64 point and join the front.
    #[test]
    fn the_pareto_front_is_joined_and_markers_follow_the_series() {
        let pts = [
            (1.0, 1e-3),
            (2.0, 1e-5),
            (3.0, 1e-4),
            (0.5, 0.0),
            (4.0, 1e-2),
            (2.5, 1e-5),
        ];
        assert_eq!(
            pareto_front(&pts, 1e-9),
            vec![(0.5, 1e-9), (2.5, 1e-5), (3.0, 1e-4), (4.0, 1e-2)]
        );
        let panel = |title: &str| Panel {
            title: title.into(),
            x_label: "x".into(),
            y_label: "y".into(),
            y_floor: 1e-9,
            pareto: true,
            series: vec![
                Series {
                    name: "a f32".into(),
                    color: "#d62728",
                    marker: Marker::Circle,
                    on_front: true,
                    points: pts[..3]
                        .iter()
                        .map(|&(x, y)| Point {
                            x,
                            y,
                            label: String::new(),
                        })
                        .collect(),
                },
                Series {
                    name: "a f64".into(),
                    color: "#1f77b4",
                    marker: Marker::Square,
                    on_front: true,
                    points: pts[3..]
                        .iter()
                        .map(|&(x, y)| Point {
                            x,
                            y,
                            label: String::new(),
                        })
                        .collect(),
                },
            ],
        };
        let doc = svg(
            &[panel("one"), panel("two"), panel("three"), panel("four")],
            3,
            &[],
        );
        assert!(!doc.contains("plot failed"), "{doc}");
        assert_eq!(
            circles(&doc, "#D62728").len(),
            4 * 3,
            "three circles a panel"
        );
        let squares = doc.matches("<rect").filter(|r| r.is_empty()).count();
        let blue_rects = doc
            .split("<rect")
            .filter(|r| r.to_ascii_uppercase().contains("FILL=\"#1F77B4\""))
            .count();
        assert_eq!(blue_rects, 4 * 3, "three squares a panel ({squares})");
        let fronts = doc
            .split("<polyline")
            .filter(|l| l.to_ascii_uppercase().contains("STROKE=\"#333333\""))
            .count();
        assert_eq!(fronts, 4, "one front a panel");
    }

    #[test]
    fn colours_parse_and_decades_cover_the_values() {
        assert_eq!(rgb("#d62728"), RGBColor(0xd6, 0x27, 0x28));
        assert_eq!(rgb("nonsense"), BLACK);
        assert_eq!(decades([0.05, 3.0].into_iter(), 0.0), (-2, 1));
        assert_eq!(decades([0.0, 1e-3].into_iter(), 1e-6), (-6, -3));
        assert_eq!(decades(std::iter::empty(), 1.0), (0, 1));
    }
}

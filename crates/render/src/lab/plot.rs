//! SVG scatter plots with logarithmic axes for the report's speed-against-error figure, drawn
//! by `plotters` (SVG backend): panels side by side, one colour per series, a label beside
//! each point, the legend below.

use plotters::coord::Shift;
use plotters::prelude::*;

/// One point: position and a short label drawn beside it.
#[derive(Clone, Debug)]
pub struct Point {
    /// Horizontal value (> 0; log axis).
    pub x: f64,
    /// Vertical value; values at or below the axis floor are drawn on the floor line.
    pub y: f64,
    /// Label.
    pub label: String,
}

/// Points drawn in one colour with one legend entry.
#[derive(Clone, Debug)]
pub struct Series {
    /// Legend name.
    pub name: String,
    /// CSS colour.
    pub color: &'static str,
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
}

/// Width and height of one panel, in pixels.
const PANEL: (u32, u32) = (520, 380);
/// Height of one legend row (three entries a row).
const LEGEND_ROW: u32 = 22;

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

/// Panels side by side as one SVG document (the legend, from the first panel's series,
/// below them).
#[must_use]
pub fn svg(panels: &[Panel]) -> String {
    let legend: Vec<(&str, &str)> = panels
        .first()
        .map(|p| {
            p.series
                .iter()
                .map(|s| (s.name.as_str(), s.color))
                .collect()
        })
        .unwrap_or_default();
    let legend_h = LEGEND_ROW * legend.len().div_ceil(3) as u32 + 10;
    let size = (PANEL.0 * panels.len().max(1) as u32, PANEL.1 + legend_h);
    let mut out = String::new();
    // Drawing into a String cannot fail for I/O; an error would mean a plotters bug, and the
    // report then carries a note instead of the figure.
    if let Err(e) = draw(&mut out, size, panels, &legend) {
        return format!(
            "<svg xmlns=\"http://www.w3.org/2000/svg\"><text y=\"20\">plot failed: {e}</text></svg>\n"
        );
    }
    out
}

fn draw(
    out: &mut String,
    size: (u32, u32),
    panels: &[Panel],
    legend: &[(&str, &str)],
) -> Result<(), Box<dyn std::error::Error>> {
    let root = SVGBackend::with_string(out, size).into_drawing_area();
    root.fill(&WHITE)?;
    let (upper, lower) = root.split_vertically(PANEL.1);
    let areas = upper.split_evenly((1, panels.len().max(1)));
    for (panel, area) in panels.iter().zip(&areas) {
        draw_panel(panel, area)?;
    }
    for (k, (name, color)) in legend.iter().enumerate() {
        let (x, y) = (
            70 + 160 * (k % 3) as i32,
            16 + LEGEND_ROW as i32 * (k / 3) as i32,
        );
        lower.draw(&Circle::new((x, y), 5, rgb(color).filled()))?;
        lower.draw(&Text::new(
            name.to_string(),
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
        .margin(16)
        .x_label_area_size(40)
        .y_label_area_size(60)
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
    for s in &panel.series {
        let color = rgb(s.color);
        let shown = s
            .points
            .iter()
            .filter(|p| p.x > 0.0 && p.x.is_finite() && !p.y.is_nan());
        chart.draw_series(shown.map(|p| {
            EmptyElement::at((p.x, p.y.max(floor)))
                + Circle::new((0, 0), 5, color.mix(0.8).filled())
                + Text::new(p.label.clone(), (7, -12), ("sans-serif", 9))
        }))?;
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
            series: vec![Series {
                name: "a<b".into(),
                color: "#d62728",
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
        let doc = svg(&[panel]);
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

    #[test]
    fn colours_parse_and_decades_cover_the_values() {
        assert_eq!(rgb("#d62728"), RGBColor(0xd6, 0x27, 0x28));
        assert_eq!(rgb("nonsense"), BLACK);
        assert_eq!(decades([0.05, 3.0].into_iter(), 0.0), (-2, 1));
        assert_eq!(decades([0.0, 1e-3].into_iter(), 1e-6), (-6, -3));
        assert_eq!(decades(std::iter::empty(), 1.0), (0, 1));
    }
}

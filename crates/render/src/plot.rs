//! Self-contained SVG scatter plots with logarithmic axes, for the report's speed-against-error
//! figure (no plotting dependency: a few dozen points need a few dozen elements).

use std::fmt::Write;

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

const W: f64 = 520.0;
const H: f64 = 380.0;
const LEFT: f64 = 70.0;
const RIGHT: f64 = 20.0;
const TOP: f64 = 40.0;
const BOTTOM: f64 = 50.0;

fn escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

/// Decades `[lo, hi]` covering the finite positive values, at least one wide.
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

/// Panels side by side as one SVG document.
#[must_use]
pub fn svg(panels: &[Panel]) -> String {
    let total_w = W * panels.len().max(1) as f64;
    let legend: Vec<(String, &str)> = panels
        .first()
        .map(|p| p.series.iter().map(|s| (s.name.clone(), s.color)).collect())
        .unwrap_or_default();
    let legend_h = 22.0 * legend.len().div_ceil(3) as f64 + 10.0;
    let mut out = String::new();
    let _ = writeln!(
        out,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{total_w}" height="{}" font-family="sans-serif" font-size="11">"#,
        H + legend_h
    );
    let _ = writeln!(out, r#"<rect width="100%" height="100%" fill="white"/>"#);
    for (i, panel) in panels.iter().enumerate() {
        panel_svg(&mut out, panel, W * i as f64);
    }
    for (k, (name, color)) in legend.iter().enumerate() {
        let (x, y) = (
            LEFT + 160.0 * (k % 3) as f64,
            H + 16.0 + 22.0 * (k / 3) as f64,
        );
        let _ = writeln!(
            out,
            r#"<circle cx="{x}" cy="{y}" r="5" fill="{color}"/><text x="{}" y="{}">{}</text>"#,
            x + 10.0,
            y + 4.0,
            escape(name)
        );
    }
    out.push_str("</svg>\n");
    out
}

fn panel_svg(out: &mut String, panel: &Panel, x0: f64) {
    let points = || panel.series.iter().flat_map(|s| s.points.iter());
    let (xa, xb) = decades(points().map(|p| p.x), 0.0);
    let (ya, yb) = decades(points().map(|p| p.y), panel.y_floor);
    let (plot_w, plot_h) = (W - LEFT - RIGHT, H - TOP - BOTTOM);
    let sx = |x: f64| x0 + LEFT + (x.log10() - f64::from(xa)) / f64::from(xb - xa) * plot_w;
    let sy = |y: f64| {
        let y = y.max(panel.y_floor);
        TOP + plot_h - (y.log10() - f64::from(ya)) / f64::from(yb - ya) * plot_h
    };
    let _ = writeln!(
        out,
        r#"<text x="{}" y="22" font-size="13" font-weight="bold">{}</text>"#,
        x0 + LEFT,
        escape(&panel.title)
    );
    let _ = writeln!(
        out,
        r##"<rect x="{}" y="{TOP}" width="{plot_w}" height="{plot_h}" fill="none" stroke="#444"/>"##,
        x0 + LEFT
    );
    for d in xa..=xb {
        let x = sx(10f64.powi(d));
        let _ = writeln!(
            out,
            r##"<line x1="{x}" y1="{TOP}" x2="{x}" y2="{}" stroke="#ddd"/><text x="{x}" y="{}" text-anchor="middle">1e{d}</text>"##,
            TOP + plot_h,
            TOP + plot_h + 15.0
        );
    }
    for d in ya..=yb {
        let y = sy(10f64.powi(d));
        let label = if f64::from(d) <= panel.y_floor.log10() {
            format!("&#8804;1e{d}")
        } else {
            format!("1e{d}")
        };
        let _ = writeln!(
            out,
            r##"<line x1="{}" y1="{y}" x2="{}" y2="{y}" stroke="#ddd"/><text x="{}" y="{}" text-anchor="end">{label}</text>"##,
            x0 + LEFT,
            x0 + LEFT + plot_w,
            x0 + LEFT - 4.0,
            y + 4.0
        );
    }
    let _ = writeln!(
        out,
        r#"<text x="{}" y="{}" text-anchor="middle">{}</text>"#,
        x0 + LEFT + plot_w / 2.0,
        H - 12.0,
        escape(&panel.x_label)
    );
    let _ = writeln!(
        out,
        r#"<text transform="translate({},{}) rotate(-90)" text-anchor="middle">{}</text>"#,
        x0 + 16.0,
        TOP + plot_h / 2.0,
        escape(&panel.y_label)
    );
    for s in &panel.series {
        for p in &s.points {
            if !(p.x > 0.0 && p.x.is_finite() && !p.y.is_nan()) {
                continue;
            }
            let (x, y) = (sx(p.x), sy(p.y));
            let _ = writeln!(
                out,
                r#"<circle cx="{x:.1}" cy="{y:.1}" r="5" fill="{}" fill-opacity="0.8"><title>{}: {} ({:.3e}, {:.3e})</title></circle><text x="{:.1}" y="{:.1}" font-size="9">{}</text>"#,
                s.color,
                escape(&s.name),
                escape(&p.label),
                p.x,
                p.y,
                x + 7.0,
                y - 5.0,
                escape(&p.label)
            );
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn points_land_inside_the_plot_and_zeros_on_the_floor() {
        let panel = Panel {
            title: "t".into(),
            x_label: "x".into(),
            y_label: "y".into(),
            y_floor: 1e-9,
            series: vec![Series {
                name: "a<b".into(),
                color: "red",
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
                ],
            }],
        };
        let doc = svg(&[panel]);
        assert!(doc.starts_with("<svg") && doc.trim_end().ends_with("</svg>"));
        assert!(doc.contains("a&lt;b") && !doc.contains("a<b"));
        let circles: Vec<(f64, f64)> = doc
            .lines()
            .filter(|l| l.starts_with("<circle cx") && l.contains("<title>"))
            .map(|l| {
                let num = |key: &str| {
                    let s = &l[l.find(key).unwrap() + key.len()..];
                    s[..s.find('"').unwrap()].parse::<f64>().unwrap()
                };
                (num("cx=\""), num("cy=\""))
            })
            .collect();
        assert_eq!(circles.len(), 2);
        for (x, y) in &circles {
            assert!((LEFT..=W - RIGHT).contains(x) && (TOP..=H - BOTTOM).contains(y));
        }
        // The zero sits on the floor: the bottom edge of the plot (floor = lowest decade).
        assert!((circles[0].1 - (H - BOTTOM)).abs() < 0.1);
        assert!(circles[1].1 < circles[0].1);
    }
}

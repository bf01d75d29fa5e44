//! Line plots of a metric's data, ours against the reference, as standalone SVG files (they open
//! in any browser or vector editor, and need nothing installed).

use std::fmt::Write as _;

/// One curve: a line through `points` (ours) or markers at them (a reference's data points).
#[derive(Clone, Debug)]
pub struct Series {
    pub label: String,
    pub points: Vec<(f64, f64)>,
    pub markers: bool,
}

/// A plot: title, axis labels, curves.
#[derive(Clone, Debug)]
pub struct Plot {
    pub title: String,
    pub x: String,
    pub y: String,
    pub series: Vec<Series>,
}

/// Drawing area inside the image, in pixels: left, top, width, height.
const AREA: (f64, f64, f64, f64) = (80.0, 40.0, 520.0, 300.0);
/// Colours of the curves, in order.
const COLOURS: [&str; 4] = ["#1f5fbf", "#d0402a", "#2a9a4a", "#8a4fbf"];

impl Plot {
    /// The plot as an SVG document; `None` when no curve has a finite point.
    pub fn svg(&self) -> Option<String> {
        let finite = |p: &&(f64, f64)| p.0.is_finite() && p.1.is_finite();
        let all: Vec<(f64, f64)> = self
            .series
            .iter()
            .flat_map(|s| s.points.iter().filter(finite).copied())
            .collect();
        let (x0, x1) = padded(all.iter().map(|p| p.0))?;
        let (y0, y1) = padded(all.iter().map(|p| p.1))?;
        let (left, top, w, h) = AREA;
        let px = |x: f64| left + (x - x0) / (x1 - x0) * w;
        let py = |y: f64| top + (1.0 - (y - y0) / (y1 - y0)) * h;
        let mut s = String::new();
        let _ = writeln!(
            s,
            "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"640\" height=\"400\" \
             font-family=\"sans-serif\" font-size=\"12\">\n<rect width=\"640\" height=\"400\" \
             fill=\"white\"/>"
        );
        let _ = writeln!(
            s,
            "<text x=\"320\" y=\"22\" text-anchor=\"middle\" font-size=\"14\">{}</text>",
            escape(&self.title)
        );
        let _ = writeln!(
            s,
            "<rect x=\"{left}\" y=\"{top}\" width=\"{w}\" height=\"{h}\" fill=\"none\" \
             stroke=\"#444\"/>"
        );
        for k in 0..=4 {
            let f = k as f64 / 4.0;
            let (x, y) = (x0 + f * (x1 - x0), y0 + f * (y1 - y0));
            let _ = writeln!(
                s,
                "<text x=\"{:.1}\" y=\"{:.1}\" text-anchor=\"middle\">{}</text>\n\
                 <text x=\"{:.1}\" y=\"{:.1}\" text-anchor=\"end\">{}</text>",
                px(x),
                top + h + 16.0,
                tick(x),
                left - 6.0,
                py(y) + 4.0,
                tick(y)
            );
        }
        let _ = writeln!(
            s,
            "<text x=\"{:.1}\" y=\"{:.1}\" text-anchor=\"middle\">{}</text>\n\
             <text transform=\"translate(18 {:.1}) rotate(-90)\" text-anchor=\"middle\">{}</text>",
            left + w / 2.0,
            top + h + 36.0,
            escape(&self.x),
            top + h / 2.0,
            escape(&self.y)
        );
        for (i, series) in self.series.iter().enumerate() {
            let colour = COLOURS[i % COLOURS.len()];
            let points: Vec<(f64, f64)> = series
                .points
                .iter()
                .filter(finite)
                .map(|&(x, y)| (px(x), py(y)))
                .collect();
            if series.markers {
                for (x, y) in &points {
                    let _ = writeln!(
                        s,
                        "<circle cx=\"{x:.1}\" cy=\"{y:.1}\" r=\"3.5\" fill=\"none\" \
                         stroke=\"{colour}\" stroke-width=\"1.5\"/>"
                    );
                }
            } else {
                let path: Vec<String> = points
                    .iter()
                    .map(|(x, y)| format!("{x:.1},{y:.1}"))
                    .collect();
                let _ = writeln!(
                    s,
                    "<polyline points=\"{}\" fill=\"none\" stroke=\"{colour}\" stroke-width=\"2\"/>",
                    path.join(" ")
                );
            }
            let ly = top + 16.0 + 18.0 * i as f64;
            let _ = writeln!(
                s,
                "<line x1=\"{:.1}\" y1=\"{ly:.1}\" x2=\"{:.1}\" y2=\"{ly:.1}\" stroke=\"{colour}\" \
                 stroke-width=\"2\"/>\n<text x=\"{:.1}\" y=\"{:.1}\">{}</text>",
                left + 10.0,
                left + 34.0,
                left + 40.0,
                ly + 4.0,
                escape(&series.label)
            );
        }
        s.push_str("</svg>\n");
        Some(s)
    }
}

/// The range of `values` widened by 5 % of its span on each side; a flat range (one value v)
/// by 1 % of max(|v|, 1).
fn padded(values: impl Iterator<Item = f64>) -> Option<(f64, f64)> {
    let (lo, hi) = values.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
        (a.min(v), b.max(v))
    });
    if !(lo.is_finite() && hi.is_finite()) {
        return None;
    }
    let span = if hi > lo {
        hi - lo
    } else {
        lo.abs().max(1.0) * 0.2
    };
    Some((lo - 0.05 * span, hi + 0.05 * span))
}

/// A tick label with four significant digits.
fn tick(v: f64) -> String {
    format!("{v:.4}")
        .trim_end_matches('0')
        .trim_end_matches('.')
        .to_string()
}

/// Text with XML's special characters escaped.
fn escape(text: &str) -> String {
    text.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn curves_map_into_the_area_and_text_is_escaped() {
        let plot = Plot {
            title: "a < b & c".into(),
            x: "t (s)".into(),
            y: "y".into(),
            series: vec![
                Series {
                    label: "ours".into(),
                    points: vec![(0.0, 0.0), (1.0, 1.0), (f64::NAN, 2.0)],
                    markers: false,
                },
                Series {
                    label: "reference".into(),
                    points: vec![(0.5, 0.5)],
                    markers: true,
                },
            ],
        };
        let svg = plot.svg().expect("finite points");
        assert!(svg.contains("a &lt; b &amp; c"));
        // x and y span 0..1 padded by 5 %: (0, 0) lands 5/110 of the area in from the lower
        // left corner, (1, 1) as far in from the upper right, (0.5, 0.5) in the middle.
        let (left, top, w, h) = AREA;
        let at = |fx: f64, fy: f64| format!("{:.1},{:.1}", left + fx * w, top + (1.0 - fy) * h);
        let (a, b) = (0.05 / 1.1, 1.05 / 1.1);
        assert!(
            svg.contains(&format!("points=\"{} {}\"", at(a, a), at(b, b))),
            "{svg}"
        );
        assert!(svg.contains(&format!(
            "cx=\"{:.1}\" cy=\"{:.1}\"",
            left + 0.5 * w,
            top + 0.5 * h
        )));
        let empty = Plot {
            series: vec![],
            ..plot
        };
        assert!(empty.svg().is_none());
    }
}

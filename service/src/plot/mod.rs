//! Minimal SVG line charts with no dependency, for the paper's figures.
//!
//! A [`Figure`] is a title over one or more [`Panel`]s stacked vertically; each panel has
//! its own axes, grid, legend and [`Series`]. That covers the three figure kinds needed:
//!
//! * a 2-D trajectory: one panel with `equal_aspect`, polylines for the estimates and a
//!   [`Style::Markers`] series with point labels for the ground-truth footprints;
//! * a time series: several lines per panel, optionally with a shaded ±σ band;
//! * stacked panels sharing the x axis ([`Figure::shared_x`]), e.g. bias x/y/z.
//!
//! Ticks are at 1-2-5 steps, colours are assigned by series order in a panel
//! (colour-blind-safe palette), non-finite points break lines and bands, long series are
//! decimated to at most [`MAX_POINTS_PER_SERIES`] points (keeping each bucket's extremes so
//! spikes survive) and all text is XML-escaped.
//!
//! ```no_run
//! use corridor_service::plot::{Figure, Panel, Series};
//! let t: Vec<f64> = (0..100).map(|i| i as f64 * 0.1).collect();
//! let b: Vec<f64> = t.iter().map(|t| (t * 0.3).sin()).collect();
//! let fig = Figure::new("Gyro bias").with_panel(
//!     Panel::new("x", "time (s)", "bias (deg/h)")
//!         .with_series(Series::line("estimate", t.clone(), b).with_band(vec![0.2; 100])),
//! );
//! fig.write_svg(std::path::Path::new("/tmp/bias.svg")).unwrap();
//! ```
//!
//! Map of the submodules: this file holds the figure model ([`Figure`], [`Panel`],
//! [`Series`], [`Style`]) and the page layout (`Figure::to_svg`); `axes` the ranges, axes
//! and 1-2-5 ticks; `render` one panel's SVG (grid, bands, lines, markers, legend), the
//! decimation and XML escaping.

mod axes;
mod render;

use axes::*;
use render::*;
use std::fmt::Write as _;
use std::path::Path;

/// Longest series written: longer ones are decimated (min/max per bucket).
pub const MAX_POINTS_PER_SERIES: usize = 4000;

/// Okabe–Ito colour-blind-safe palette (yellow left out: unreadable on white).
const PALETTE: [&str; 7] = [
    "#0072B2", "#D55E00", "#009E73", "#CC79A7", "#E69F00", "#56B4E9", "#000000",
];

const FONT: &str = "DejaVu Sans, Helvetica, Arial, sans-serif";
const CHAR_W: f64 = 6.8; // rough width of one 12 px character, for layout only
const LEFT: f64 = 78.0;
const BOTTOM: f64 = 50.0;
const RIGHT_PAD: f64 = 16.0;

/// How a series is drawn.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Style {
    /// Solid polyline.
    #[default]
    Line,
    /// Dashed polyline.
    Dashed,
    /// A filled circle at each point, no line.
    Markers,
}

/// One data series of a panel.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Series {
    /// Legend text; an empty label keeps the series out of the legend.
    pub label: String,
    /// x values.
    pub x: Vec<f64>,
    /// y values (same length as `x`; extra values of either are ignored).
    pub y: Vec<f64>,
    /// Optional ± half-width per point, drawn as a shaded band around the line
    /// (missing or non-finite values break the band).
    pub band: Option<Vec<f64>>,
    /// Line, dashed line or markers.
    pub style: Style,
    /// Optional text drawn next to each point (e.g. GCP numbers); empty strings draw nothing.
    pub point_labels: Option<Vec<String>>,
}

impl Series {
    /// A series with the given style and no band or point labels.
    pub fn new(label: impl Into<String>, x: Vec<f64>, y: Vec<f64>, style: Style) -> Self {
        Self {
            label: label.into(),
            x,
            y,
            style,
            band: None,
            point_labels: None,
        }
    }

    /// A solid line.
    pub fn line(label: impl Into<String>, x: Vec<f64>, y: Vec<f64>) -> Self {
        Self::new(label, x, y, Style::Line)
    }

    /// A dashed line.
    pub fn dashed(label: impl Into<String>, x: Vec<f64>, y: Vec<f64>) -> Self {
        Self::new(label, x, y, Style::Dashed)
    }

    /// Markers only.
    pub fn markers(label: impl Into<String>, x: Vec<f64>, y: Vec<f64>) -> Self {
        Self::new(label, x, y, Style::Markers)
    }

    /// Adds a shaded ± band (half-width per point).
    pub fn with_band(mut self, half_width: Vec<f64>) -> Self {
        self.band = Some(half_width);
        self
    }

    /// Adds a text label per point.
    pub fn with_point_labels(mut self, labels: Vec<String>) -> Self {
        self.point_labels = Some(labels);
        self
    }
}

/// One set of axes.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Panel {
    /// Title above the panel (may be empty).
    pub title: String,
    /// x-axis label (may be empty, e.g. on all but the bottom of stacked panels).
    pub x_label: String,
    /// y-axis label.
    pub y_label: String,
    /// The series, drawn in order (later on top); colours follow this order.
    pub series: Vec<Series>,
    /// One x unit spans as many pixels as one y unit (for trajectories).
    pub equal_aspect: bool,
}

impl Panel {
    /// An empty panel with the given title and axis labels.
    pub fn new(
        title: impl Into<String>,
        x_label: impl Into<String>,
        y_label: impl Into<String>,
    ) -> Self {
        Self {
            title: title.into(),
            x_label: x_label.into(),
            y_label: y_label.into(),
            ..Self::default()
        }
    }

    /// Appends a series.
    pub fn with_series(mut self, s: Series) -> Self {
        self.series.push(s);
        self
    }

    /// Turns on equal aspect.
    pub fn with_equal_aspect(mut self) -> Self {
        self.equal_aspect = true;
        self
    }
}

/// A figure: a title and panels stacked vertically.
#[derive(Debug, Clone, PartialEq)]
pub struct Figure {
    /// Title on top (may be empty).
    pub title: String,
    /// Panels, top to bottom.
    pub panels: Vec<Panel>,
    /// Total width, pixels.
    pub width_px: u32,
    /// Height of each panel including its title and axis labels, pixels.
    pub panel_height_px: u32,
    /// All panels without equal aspect use one x range (the union of their data).
    pub shared_x: bool,
}

impl Default for Figure {
    fn default() -> Self {
        Self {
            title: String::new(),
            panels: Vec::new(),
            width_px: 900,
            panel_height_px: 320,
            shared_x: false,
        }
    }
}

/// A series after decimation, with its colour.
struct Prepared<'a> {
    s: &'a Series,
    idx: Vec<usize>,
    color: &'static str,
}

impl Prepared<'_> {
    fn x(&self, k: usize) -> f64 {
        self.s.x[self.idx[k]]
    }
    fn y(&self, k: usize) -> f64 {
        self.s.y[self.idx[k]]
    }
    fn band(&self, k: usize) -> f64 {
        self.s
            .band
            .as_ref()
            .and_then(|b| b.get(self.idx[k]).copied())
            .unwrap_or(f64::NAN)
    }
}

impl Figure {
    /// An empty figure with the default size (900 px wide, 320 px per panel).
    pub fn new(title: impl Into<String>) -> Self {
        Self {
            title: title.into(),
            ..Self::default()
        }
    }

    /// Appends a panel.
    pub fn with_panel(mut self, p: Panel) -> Self {
        self.panels.push(p);
        self
    }

    /// Sets the size in pixels.
    pub fn with_size(mut self, width_px: u32, panel_height_px: u32) -> Self {
        self.width_px = width_px;
        self.panel_height_px = panel_height_px;
        self
    }

    /// Shares one x range between the panels (see [`Figure::shared_x`]).
    pub fn with_shared_x(mut self) -> Self {
        self.shared_x = true;
        self
    }

    /// Renders the figure as a standalone SVG document.
    pub fn to_svg(&self) -> String {
        let w = f64::from(self.width_px.max(200));
        let ph = f64::from(self.panel_height_px.max(120));
        let title_h = if self.title.is_empty() { 6.0 } else { 34.0 };
        let h = title_h + ph * self.panels.len() as f64 + 4.0;

        let prepared: Vec<Vec<Prepared>> = self
            .panels
            .iter()
            .map(|p| {
                p.series
                    .iter()
                    .enumerate()
                    .map(|(i, s)| Prepared {
                        s,
                        idx: decimate(&s.x, &s.y, MAX_POINTS_PER_SERIES),
                        color: PALETTE[i % PALETTE.len()],
                    })
                    .collect()
            })
            .collect();

        // One legend width for all panels so stacked plot areas line up.
        let max_label = self
            .panels
            .iter()
            .flat_map(|p| &p.series)
            .map(|s| s.label.chars().count())
            .max()
            .unwrap_or(0);
        let legend_w = if max_label == 0 {
            0.0
        } else {
            (44.0 + CHAR_W * max_label as f64).min(w * 0.35)
        };
        let (plot_l, plot_r) = (LEFT, w - RIGHT_PAD - legend_w);

        let shared = if self.shared_x {
            prepared
                .iter()
                .zip(&self.panels)
                .filter(|(_, p)| !p.equal_aspect)
                .map(|(s, _)| data_range(s).0)
                .reduce(union)
        } else {
            None
        };

        let mut o = String::new();
        let _ = write!(
            o,
            r#"<svg xmlns="http://www.w3.org/2000/svg" width="{w}" height="{h}" viewBox="0 0 {w} {h}" font-family="{FONT}" font-size="12">"#
        );
        o.push('\n');
        let _ = writeln!(o, r#"<rect width="{w}" height="{h}" fill="white"/>"#);
        if !self.title.is_empty() {
            let _ = writeln!(
                o,
                r#"<text x="{:.1}" y="23" text-anchor="middle" font-size="16" font-weight="bold">{}</text>"#,
                w / 2.0,
                esc(&self.title)
            );
        }
        for (i, (panel, series)) in self.panels.iter().zip(&prepared).enumerate() {
            let top = title_h + ph * i as f64;
            let plot_t = top + if panel.title.is_empty() { 12.0 } else { 30.0 };
            let plot_b = top + ph - BOTTOM;
            let rect = Rect {
                l: plot_l,
                r: plot_r,
                t: plot_t,
                b: plot_b,
            };
            render_panel(&mut o, i, panel, series, rect, shared, top);
        }
        o.push_str("</svg>\n");
        o
    }

    /// Writes [`Figure::to_svg`] to `path`.
    pub fn write_svg(&self, path: &Path) -> std::io::Result<()> {
        std::fs::write(path, self.to_svg())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Checks that every tag is closed in order; returns the root element's name.
    fn balanced(svg: &str) -> Result<String, String> {
        let mut stack: Vec<String> = Vec::new();
        let mut root = None;
        let mut rest = svg;
        while let Some(i) = rest.find('<') {
            rest = &rest[i + 1..];
            let end = rest.find('>').ok_or("unterminated tag")?;
            let tag = &rest[..end];
            rest = &rest[end + 1..];
            if tag.starts_with('?') || tag.starts_with('!') {
                continue;
            }
            if let Some(name) = tag.strip_prefix('/') {
                let open = stack.pop().ok_or(format!("stray </{name}>"))?;
                if open != name.trim() {
                    return Err(format!("<{open}> closed by </{name}>"));
                }
                continue;
            }
            let name = tag
                .split_whitespace()
                .next()
                .unwrap_or("")
                .trim_end_matches('/');
            if root.is_none() {
                root = Some(name.to_owned());
            } else if stack.is_empty() {
                return Err(format!("second root <{name}>"));
            }
            if !tag.ends_with('/') {
                stack.push(name.to_owned());
            }
        }
        if !stack.is_empty() {
            return Err(format!("unclosed {stack:?}"));
        }
        if svg.contains('&') {
            for part in svg.split('&').skip(1) {
                let ent = part.split(';').next().unwrap_or("");
                if !["amp", "lt", "gt", "quot", "apos"].contains(&ent) {
                    return Err(format!("bad entity &{ent}"));
                }
            }
        }
        root.ok_or_else(|| "empty".to_owned())
    }

    fn example() -> Figure {
        let t: Vec<f64> = (0..2000).map(|i| i as f64 * 0.05).collect();
        let traj_x: Vec<f64> = t.iter().map(|t| 10.0 * (t * 0.063).sin()).collect();
        let traj_y: Vec<f64> = t.iter().map(|t| 5.0 - 5.0 * (t * 0.063).cos()).collect();
        let bias: Vec<f64> = t
            .iter()
            .map(|&t| {
                if (40.0..42.0).contains(&t) {
                    f64::NAN
                } else {
                    3.0 * (t * 0.05).sin()
                }
            })
            .collect();
        Figure::new("Trajectory & bias <test>")
            .with_panel(
                Panel::new("Plan view", "x (m)", "y (m)")
                    .with_equal_aspect()
                    .with_series(Series::line("uncorrected", traj_x.clone(), traj_y.clone()))
                    .with_series(Series::dashed(
                        "corrected",
                        traj_x.iter().map(|v| v * 0.9).collect(),
                        traj_y.clone(),
                    ))
                    .with_series(
                        Series::markers("GCPs", vec![0.0, 10.0, 0.0], vec![0.0, 5.0, 10.0])
                            .with_point_labels(vec!["G0".into(), "G1".into(), "G2 \"end\"".into()]),
                    ),
            )
            .with_panel(
                Panel::new("Bias x", "", "bias (deg/h)").with_series(
                    Series::line("estimate", t.clone(), bias).with_band(vec![0.5; 2000]),
                ),
            )
            .with_panel(
                Panel::new("Bias y", "time (s)", "bias (deg/h)").with_series(Series::line(
                    "estimate",
                    t.clone(),
                    vec![1.0; 2000],
                )),
            )
            .with_shared_x()
    }

    #[test]
    fn svg_is_balanced_and_has_the_labels() {
        let svg = example().to_svg();
        assert_eq!(balanced(&svg).unwrap(), "svg");
        for s in [
            "Trajectory &amp; bias &lt;test&gt;",
            "Plan view",
            "x (m)",
            "y (m)",
            "uncorrected",
            "corrected",
            "GCPs",
            "G2 &quot;end&quot;",
            "bias (deg/h)",
            "time (s)",
            "stroke-dasharray",
            "fill-opacity=\"0.2\"",
        ] {
            assert!(svg.contains(s), "missing {s}");
        }
        assert!(!svg.contains("<test>"));
    }

    #[test]
    fn non_finite_points_break_lines_without_nan_in_output() {
        let x = vec![0.0, 1.0, 2.0, f64::NAN, 4.0, 5.0, 6.0, 7.0];
        let y = vec![0.0, 1.0, f64::INFINITY, 3.0, 4.0, 5.0, f64::NAN, 7.0];
        let band = vec![0.1, 0.1, 0.1, 0.1, f64::NAN, 0.1, 0.1];
        let fig = Figure::new("gaps").with_panel(
            Panel::new("", "x", "y")
                .with_series(Series::line("a", x.clone(), y.clone()).with_band(band))
                .with_series(Series::markers("b", x, y)),
        );
        let svg = fig.to_svg();
        balanced(&svg).unwrap();
        let lower = svg.to_lowercase();
        assert!(!lower.contains("nan") && !lower.contains("inf"), "{svg}");
        // Runs {0,1}, {4,5}, {7}: two moves in the line's path (the lone point has no
        // segment but still starts a subpath).
        let line = svg
            .lines()
            .find(|l| l.contains("stroke-width=\"1.6\" stroke-linejoin"))
            .unwrap();
        assert_eq!(line.matches('M').count(), 3, "{line}");
        // 5 finite markers.
        assert_eq!(svg.matches("<circle cx").count(), 5 + 1); // + legend marker
    }

    #[test]
    fn ticks_are_1_2_5_steps_covering_the_range() {
        let cases = [
            (0.13, 9.7),
            (-3.2, 47.0),
            (1e-5, 3.3e-4),
            (-250.0, -249.2),
            (0.0, 1.0),
            (17.0, 17.0),
            (-1e6, 2e6),
        ];
        for (lo, hi) in cases {
            for target in [2, 5, 8] {
                let (t, step) = nice_ticks(lo, hi, target);
                assert!(t[0] <= lo && *t.last().unwrap() >= hi, "{lo} {hi} {t:?}");
                let e = step.log10().floor();
                let m = step / 10f64.powf(e);
                assert!(
                    [1.0, 2.0, 5.0, 10.0].iter().any(|c| (m - c).abs() < 1e-9),
                    "step {step}"
                );
                for w in t.windows(2) {
                    assert!(((w[1] - w[0]) - step).abs() < step * 1e-6, "{t:?}");
                }
                assert!(
                    t.len() >= 2 && t.len() <= 3 * target + 3,
                    "{lo} {hi} {target} {t:?}"
                );
                // Multiples of the step, so labels are round.
                for v in &t {
                    assert!(((v / step) - (v / step).round()).abs() < 1e-6);
                }
            }
        }
        assert_eq!(
            nice_ticks(0.13, 9.7, 5).0,
            vec![0.0, 2.0, 4.0, 6.0, 8.0, 10.0]
        );
        assert_eq!(tick_label(0.30000000000000004, 0.1), "0.3");
        assert_eq!(tick_label(-0.0, 0.5), "0.0");
        assert_eq!(tick_label(2000.0, 500.0), "2000");
    }

    /// A log stamped in Unix seconds (`t_s` from 1.7e9, which the reader takes): every time
    /// tick of `corridor run --plots` and `corridor diagnose` read "1.7e9" (a review).
    #[test]
    fn ticks_of_large_values_a_small_step_apart_are_told_apart() {
        for (lo, hi) in [
            (1.7e9, 1.7e9 + 70.0),
            (1.7e9, 1.7e9 + 0.8),
            (2.0e6, 2.0e6 + 45.0),
        ] {
            let (ticks, step) = nice_ticks(lo, hi, 8);
            let labels: Vec<String> = ticks.iter().map(|&t| tick_label(t, step)).collect();
            for (t, l) in ticks.iter().zip(&labels) {
                let back: f64 = l.parse().unwrap_or(f64::NAN);
                assert!(
                    (back - t).abs() < step * 0.01,
                    "{t} labelled {l:?} (step {step})"
                );
            }
            let mut distinct = labels.clone();
            distinct.dedup();
            assert_eq!(distinct.len(), labels.len(), "{labels:?}");
        }
        // Large values ticked coarsely keep their short form, small ones theirs.
        assert_eq!(tick_label(2.0e9, 5.0e8), "2.0e9");
        assert_eq!(tick_label(1.2e-4, 2.0e-5), "1.2e-4");
    }

    #[test]
    fn decimation_keeps_extremes_and_gaps() {
        let n = 100_000;
        let x: Vec<f64> = (0..n).map(|i| i as f64).collect();
        let mut y: Vec<f64> = x.iter().map(|v| (v * 0.001).sin()).collect();
        y[12_345] = 50.0;
        y[77_777] = -40.0;
        y[50_000] = f64::NAN;
        let idx = decimate(&x, &y, MAX_POINTS_PER_SERIES);
        assert!(idx.len() <= MAX_POINTS_PER_SERIES, "{}", idx.len());
        assert!(idx.windows(2).all(|w| w[0] < w[1]));
        for must in [0, n - 1, 12_345, 77_777, 50_000] {
            assert!(idx.contains(&must), "{must}");
        }
        // Short series are untouched.
        assert_eq!(
            decimate(&x[..10], &y[..10], 4000),
            (0..10).collect::<Vec<_>>()
        );
        // And the path written for the long series respects the limit.
        let fig = Figure::new("").with_panel(Panel::new("", "", "").with_series(Series::line(
            "s",
            x.clone(),
            y.clone(),
        )));
        let svg = fig.to_svg();
        let path = svg.lines().find(|l| l.starts_with("<path d=\"M")).unwrap();
        assert!(path.matches('L').count() + path.matches('M').count() <= MAX_POINTS_PER_SERIES);
    }

    #[test]
    fn equal_aspect_gives_equal_scales() {
        let (ax, ay) = equal_axes((0.0, 20.0), (0.0, 5.0), 600.0, 300.0, 6, 6);
        let sx = 600.0 / (ax.hi - ax.lo);
        let sy = 300.0 / (ay.hi - ay.lo);
        assert!((sx - sy).abs() < 1e-9 * sx);
        assert!(ax.lo <= 0.0 && ax.hi >= 20.0 && ay.lo <= 0.0 && ay.hi >= 5.0);
        assert!(ax.ticks.len() >= 2 && ay.ticks.len() >= 2);
        assert!((ax.step - ay.step).abs() < 1e-12);
    }

    #[test]
    fn empty_figure_and_empty_series_are_valid() {
        let svg = Figure::new("").to_svg();
        assert_eq!(balanced(&svg).unwrap(), "svg");
        let fig = Figure::new("e").with_panel(Panel::new("p", "x", "y").with_series(Series::line(
            "none",
            vec![],
            vec![],
        )));
        assert_eq!(balanced(&fig.to_svg()).unwrap(), "svg");
    }

    /// `write_svg` writes exactly `to_svg`, at the size asked for. With CORRIDOR_PLOT_EXAMPLE
    /// set to a file path, the example figure is also written there, to look at.
    #[test]
    fn write_svg_writes_the_figure_at_its_size() {
        let fig = example().with_size(640, 200);
        let dir = std::env::temp_dir().join(format!("corridor-plot-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("example.svg");
        let written = fig
            .write_svg(&path)
            .and_then(|()| std::fs::read_to_string(&path));
        std::fs::remove_dir_all(&dir).unwrap();
        let written = written.unwrap();
        assert_eq!(written, fig.to_svg());
        assert_eq!(balanced(&written).unwrap(), "svg");
        assert!(written.contains("width=\"640\""), "{}", &written[..200]);
        assert!(!example().to_svg().contains("width=\"640\""));
        if let Ok(p) = std::env::var("CORRIDOR_PLOT_EXAMPLE") {
            fig.write_svg(Path::new(&p)).unwrap();
        }
    }
}

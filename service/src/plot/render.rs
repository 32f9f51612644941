//! One panel's SVG: grid, bands, lines, markers and legend; the decimation of long series and
//! the XML escaping of text.

use super::axes::*;
use super::*;

#[derive(Debug, Clone, Copy)]
pub(super) struct Rect {
    pub(super) l: f64,
    pub(super) r: f64,
    pub(super) t: f64,
    pub(super) b: f64,
}

/// Escapes text for XML content and attribute values.
pub(super) fn esc(s: &str) -> String {
    let mut o = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => o.push_str("&amp;"),
            '<' => o.push_str("&lt;"),
            '>' => o.push_str("&gt;"),
            '"' => o.push_str("&quot;"),
            '\'' => o.push_str("&apos;"),
            c if (c as u32) < 0x20 && c != '\t' && c != '\n' && c != '\r' => {}
            c => o.push(c),
        }
    }
    o
}

/// Indices of the points kept when a series has more than `max_points` points: the
/// series is cut into buckets and each bucket keeps the points with its smallest and
/// largest x and y (so spikes survive in both directions) and its first non-finite point
/// (so gaps survive), in their original order.
pub(super) fn decimate(x: &[f64], y: &[f64], max_points: usize) -> Vec<usize> {
    let n = x.len().min(y.len());
    if n <= max_points {
        return (0..n).collect();
    }
    let buckets = (max_points / 5).max(1);
    let size = n.div_ceil(buckets);
    let mut keep = Vec::with_capacity(max_points);
    for a in (0..n).step_by(size) {
        let b = (a + size).min(n);
        let mut pick: [Option<usize>; 5] = [None; 5];
        let better = |cur: Option<usize>, i: usize, v: &[f64], less: bool| match cur {
            None => Some(i),
            Some(c) if (less && v[i] < v[c]) || (!less && v[i] > v[c]) => Some(i),
            keep => keep,
        };
        for i in a..b {
            if !(x[i].is_finite() && y[i].is_finite()) {
                pick[4] = pick[4].or(Some(i));
                continue;
            }
            pick[0] = better(pick[0], i, x, true);
            pick[1] = better(pick[1], i, x, false);
            pick[2] = better(pick[2], i, y, true);
            pick[3] = better(pick[3], i, y, false);
        }
        let mut p: Vec<usize> = pick.iter().flatten().copied().collect();
        p.sort_unstable();
        p.dedup();
        keep.extend(p);
    }
    keep
}

pub(super) fn render_panel(
    o: &mut String,
    index: usize,
    panel: &Panel,
    series: &[Prepared],
    r: Rect,
    shared_x: Option<Range>,
    top: f64,
) {
    let (w, h) = (r.r - r.l, r.b - r.t);
    let (xr, yr) = data_range(series);
    let tx = ((w / 90.0) as usize).clamp(2, 12);
    let ty = ((h / 45.0) as usize).clamp(2, 10);
    let (ax, ay) = if panel.equal_aspect {
        equal_axes(xr, yr, w, h, tx, ty)
    } else {
        let yr = pad(yr, 0.04);
        let ay = axis_exact(yr, nice_step(yr.1 - yr.0, ty));
        (axis_for(shared_x.unwrap_or(xr), tx), ay)
    };
    let px = |v: f64| ax.px(v, r.l, r.r);
    let py = |v: f64| ay.px(v, r.b, r.t);

    let _ = writeln!(o, r#"<g id="panel{index}">"#);
    let _ = writeln!(
        o,
        r#"<defs><clipPath id="clip{index}"><rect x="{:.2}" y="{:.2}" width="{:.2}" height="{:.2}"/></clipPath></defs>"#,
        r.l, r.t, w, h
    );
    if !panel.title.is_empty() {
        let _ = writeln!(
            o,
            r#"<text x="{:.2}" y="{:.2}" font-size="13" font-weight="bold">{}</text>"#,
            r.l,
            top + 21.0,
            esc(&panel.title)
        );
    }
    // Grid, ticks and tick labels.
    o.push_str(r##"<g stroke="#e3e3e3" stroke-width="1">"##);
    for &t in &ax.ticks {
        let x = px(t);
        let _ = write!(
            o,
            r#"<line x1="{x:.2}" y1="{:.2}" x2="{x:.2}" y2="{:.2}"/>"#,
            r.t, r.b
        );
    }
    for &t in &ay.ticks {
        let y = py(t);
        let _ = write!(
            o,
            r#"<line x1="{:.2}" y1="{y:.2}" x2="{:.2}" y2="{y:.2}"/>"#,
            r.l, r.r
        );
    }
    o.push_str("</g>\n");
    o.push_str(r##"<g font-size="11" fill="#333">"##);
    for &t in &ax.ticks {
        let _ = write!(
            o,
            r#"<text x="{:.2}" y="{:.2}" text-anchor="middle">{}</text>"#,
            px(t),
            r.b + 16.0,
            esc(&tick_label(t, ax.step))
        );
    }
    for &t in &ay.ticks {
        let _ = write!(
            o,
            r#"<text x="{:.2}" y="{:.2}" text-anchor="end">{}</text>"#,
            r.l - 6.0,
            py(t) + 4.0,
            esc(&tick_label(t, ay.step))
        );
    }
    o.push_str("</g>\n");
    if !panel.x_label.is_empty() {
        let _ = writeln!(
            o,
            r#"<text x="{:.2}" y="{:.2}" text-anchor="middle">{}</text>"#,
            (r.l + r.r) / 2.0,
            r.b + 36.0,
            esc(&panel.x_label)
        );
    }
    if !panel.y_label.is_empty() {
        let _ = writeln!(
            o,
            r#"<text transform="translate({:.2},{:.2}) rotate(-90)" text-anchor="middle">{}</text>"#,
            r.l - 58.0,
            (r.t + r.b) / 2.0,
            esc(&panel.y_label)
        );
    }

    // Data: bands first so every line is on top of every band.
    let _ = writeln!(o, r#"<g clip-path="url(#clip{index})">"#);
    for s in series.iter().filter(|s| s.s.band.is_some()) {
        for run in runs(s.idx.len(), |k| {
            s.x(k).is_finite() && s.y(k).is_finite() && s.band(k).is_finite()
        }) {
            let mut d = String::new();
            for k in run.clone() {
                let cmd = if k == run.start { 'M' } else { 'L' };
                let _ = write!(
                    d,
                    "{cmd}{:.2},{:.2}",
                    px(s.x(k)),
                    py(s.y(k) + s.band(k).abs())
                );
            }
            for k in run.clone().rev() {
                let _ = write!(d, "L{:.2},{:.2}", px(s.x(k)), py(s.y(k) - s.band(k).abs()));
            }
            let _ = writeln!(
                o,
                r#"<path d="{d}Z" fill="{}" fill-opacity="0.2" stroke="none"/>"#,
                s.color
            );
        }
    }
    for s in series.iter().filter(|s| s.s.style != Style::Markers) {
        let mut d = String::new();
        for run in runs(s.idx.len(), |k| s.x(k).is_finite() && s.y(k).is_finite()) {
            for k in run.clone() {
                let cmd = if k == run.start { 'M' } else { 'L' };
                let _ = write!(d, "{cmd}{:.2},{:.2}", px(s.x(k)), py(s.y(k)));
            }
        }
        if d.is_empty() {
            continue;
        }
        let dash = if s.s.style == Style::Dashed {
            r#" stroke-dasharray="7 4""#
        } else {
            ""
        };
        let _ = writeln!(
            o,
            r#"<path d="{d}" fill="none" stroke="{}" stroke-width="1.6" stroke-linejoin="round"{dash}/>"#,
            s.color
        );
    }
    o.push_str("</g>\n");
    for s in series.iter().filter(|s| s.s.style == Style::Markers) {
        let _ = write!(
            o,
            r#"<g fill="{}" stroke="white" stroke-width="0.8">"#,
            s.color
        );
        for k in 0..s.idx.len() {
            let (x, y) = (s.x(k), s.y(k));
            if x.is_finite() && y.is_finite() {
                let _ = write!(
                    o,
                    r#"<circle cx="{:.2}" cy="{:.2}" r="3.6"/>"#,
                    px(x),
                    py(y)
                );
            }
        }
        o.push_str("</g>\n");
    }
    for s in series {
        let Some(labels) = &s.s.point_labels else {
            continue;
        };
        let _ = write!(o, r#"<g font-size="10" fill="{}">"#, s.color);
        for k in 0..s.idx.len() {
            let (x, y) = (s.x(k), s.y(k));
            match labels.get(s.idx[k]) {
                Some(l) if !l.is_empty() && x.is_finite() && y.is_finite() => {
                    let _ = write!(
                        o,
                        r#"<text x="{:.2}" y="{:.2}">{}</text>"#,
                        px(x) + 5.0,
                        py(y) - 5.0,
                        esc(l)
                    );
                }
                _ => {}
            }
        }
        o.push_str("</g>\n");
    }
    let _ = writeln!(
        o,
        r##"<rect x="{:.2}" y="{:.2}" width="{w:.2}" height="{h:.2}" fill="none" stroke="#444" stroke-width="1"/>"##,
        r.l, r.t
    );

    // Legend, right of the plot area.
    let lx = r.r + 12.0;
    let mut ly = r.t + 8.0;
    for s in series.iter().filter(|s| !s.s.label.is_empty()) {
        if s.s.band.is_some() {
            let _ = write!(
                o,
                r#"<rect x="{lx:.2}" y="{:.2}" width="26" height="10" fill="{}" fill-opacity="0.2"/>"#,
                ly - 5.0,
                s.color
            );
        }
        match s.s.style {
            Style::Markers => {
                let _ = write!(
                    o,
                    r#"<circle cx="{:.2}" cy="{ly:.2}" r="3.6" fill="{}"/>"#,
                    lx + 13.0,
                    s.color
                );
            }
            style => {
                let dash = if style == Style::Dashed {
                    r#" stroke-dasharray="7 4""#
                } else {
                    ""
                };
                let _ = write!(
                    o,
                    r#"<line x1="{lx:.2}" y1="{ly:.2}" x2="{:.2}" y2="{ly:.2}" stroke="{}" stroke-width="1.6"{dash}/>"#,
                    lx + 26.0,
                    s.color
                );
            }
        }
        let _ = writeln!(
            o,
            r#"<text x="{:.2}" y="{:.2}">{}</text>"#,
            lx + 32.0,
            ly + 4.0,
            esc(&s.s.label)
        );
        ly += 18.0;
    }
    o.push_str("</g>\n");
}

/// Maximal runs of consecutive indices in `0..n` for which `ok` holds.
pub(super) fn runs(n: usize, ok: impl Fn(usize) -> bool) -> Vec<std::ops::Range<usize>> {
    let mut out = Vec::new();
    let mut start = None;
    for k in 0..=n {
        match (k < n && ok(k), start) {
            (true, None) => start = Some(k),
            (false, Some(s)) => {
                out.push(s..k);
                start = None;
            }
            _ => {}
        }
    }
    out
}

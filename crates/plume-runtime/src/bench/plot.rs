//! The accuracy plot: position error against time per step, log-log, one series per
//! integrator, the Pareto front marked. Plain SVG, written directly.

use std::fmt::Write;

use crate::bench::accuracy::{pareto_front, AccuracyRow};

const W: f64 = 760.0;
const H: f64 = 480.0;
const LEFT: f64 = 80.0;
const RIGHT: f64 = 170.0;
const TOP: f64 = 40.0;
const BOTTOM: f64 = 60.0;
const COLORS: [&str; 6] = [
    "#d62728", "#ff7f0e", "#2ca02c", "#1f77b4", "#9467bd", "#444444",
];

/// Decade range [10^lo, 10^hi] covering the positive values.
fn decades(values: impl Iterator<Item = f64>) -> (f64, f64) {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for v in values.filter(|v| *v > 0.0 && v.is_finite()) {
        lo = lo.min(v.log10());
        hi = hi.max(v.log10());
    }
    if !lo.is_finite() {
        return (-1.0, 0.0);
    }
    let (lo, hi) = (lo.floor(), hi.ceil());
    (lo, if hi > lo { hi } else { lo + 1.0 })
}

/// The SVG text of the plot; `title` goes on top.
pub fn accuracy_svg(rows: &[AccuracyRow], title: &str) -> String {
    let (x0, x1) = decades(rows.iter().map(|r| r.seconds_per_step));
    let (y0, y1) = decades(rows.iter().map(|r| r.max_error));
    let px = |v: f64| LEFT + (v.log10() - x0) / (x1 - x0) * (W - LEFT - RIGHT);
    let py = |v: f64| H - BOTTOM - (v.log10() - y0) / (y1 - y0) * (H - TOP - BOTTOM);
    let mut s = String::new();
    let _ = writeln!(
        s,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{W}" height="{H}" viewBox="0 0 {W} {H}" font-family="sans-serif" font-size="12">"#
    );
    let _ = writeln!(s, r#"<rect width="{W}" height="{H}" fill="white"/>"#);
    let _ = writeln!(
        s,
        r#"<text x="{}" y="22" font-size="15" text-anchor="middle">{}</text>"#,
        (LEFT + W - RIGHT) / 2.0,
        escape(title)
    );
    // Decade grid and labels.
    for d in (x0 as i32)..=(x1 as i32) {
        let x = px(10f64.powi(d));
        let _ = writeln!(
            s,
            r##"<line x1="{x}" y1="{TOP}" x2="{x}" y2="{}" stroke="#ddd"/>"##,
            H - BOTTOM
        );
        let _ = writeln!(
            s,
            r#"<text x="{x}" y="{}" text-anchor="middle">1e{d}</text>"#,
            H - BOTTOM + 18.0
        );
    }
    for d in (y0 as i32)..=(y1 as i32) {
        let y = py(10f64.powi(d));
        let _ = writeln!(
            s,
            r##"<line x1="{LEFT}" y1="{y}" x2="{}" y2="{y}" stroke="#ddd"/>"##,
            W - RIGHT
        );
        let _ = writeln!(
            s,
            r#"<text x="{}" y="{}" text-anchor="end">1e{d}</text>"#,
            LEFT - 6.0,
            y + 4.0
        );
    }
    let _ = writeln!(
        s,
        r#"<rect x="{LEFT}" y="{TOP}" width="{}" height="{}" fill="none" stroke="black"/>"#,
        W - LEFT - RIGHT,
        H - TOP - BOTTOM
    );
    let _ = writeln!(
        s,
        r#"<text x="{}" y="{}" text-anchor="middle">time per step (s)</text>"#,
        (LEFT + W - RIGHT) / 2.0,
        H - 18.0
    );
    let _ = writeln!(
        s,
        r#"<text transform="translate(20 {}) rotate(-90)" text-anchor="middle">max position error (m)</text>"#,
        (TOP + H - BOTTOM) / 2.0
    );
    // One series per integrator, in the order they first appear.
    let mut names: Vec<&str> = Vec::new();
    for r in rows {
        if !names.contains(&r.integrator.name()) {
            names.push(r.integrator.name());
        }
    }
    for (k, name) in names.iter().enumerate() {
        let color = COLORS[k % COLORS.len()];
        let pts: Vec<(f64, f64)> = rows
            .iter()
            .filter(|r| r.integrator.name() == *name && r.max_error > 0.0)
            .map(|r| (px(r.seconds_per_step), py(r.max_error)))
            .collect();
        let path: Vec<String> = pts.iter().map(|(x, y)| format!("{x:.1},{y:.1}")).collect();
        let _ = writeln!(
            s,
            r#"<polyline points="{}" fill="none" stroke="{color}" stroke-width="1.5"/>"#,
            path.join(" ")
        );
        for (x, y) in &pts {
            let _ = writeln!(
                s,
                r#"<circle cx="{x:.1}" cy="{y:.1}" r="3.5" fill="{color}"/>"#
            );
        }
        let ly = TOP + 16.0 + 18.0 * k as f64;
        let lx = W - RIGHT + 14.0;
        let _ = writeln!(
            s,
            r#"<circle cx="{lx}" cy="{}" r="4" fill="{color}"/><text x="{}" y="{}">{name}</text>"#,
            ly - 4.0,
            lx + 10.0,
            ly
        );
    }
    // The Pareto front: ringed points joined by a dashed line, fastest first.
    let mut front: Vec<&AccuracyRow> = pareto_front(rows)
        .into_iter()
        .map(|i| &rows[i])
        .filter(|r| r.max_error > 0.0)
        .collect();
    front.sort_by(|a, b| a.seconds_per_step.total_cmp(&b.seconds_per_step));
    let path: Vec<String> = front
        .iter()
        .map(|r| format!("{:.1},{:.1}", px(r.seconds_per_step), py(r.max_error)))
        .collect();
    let _ = writeln!(
        s,
        r#"<polyline points="{}" fill="none" stroke="black" stroke-dasharray="5 4"/>"#,
        path.join(" ")
    );
    for r in &front {
        let _ = writeln!(
            s,
            r#"<circle cx="{:.1}" cy="{:.1}" r="7" fill="none" stroke="black"/>"#,
            px(r.seconds_per_step),
            py(r.max_error)
        );
    }
    let ly = TOP + 16.0 + 18.0 * names.len() as f64 + 8.0;
    let _ = writeln!(
        s,
        r#"<circle cx="{}" cy="{}" r="6" fill="none" stroke="black"/><text x="{}" y="{ly}">Pareto front</text>"#,
        W - RIGHT + 14.0,
        ly - 4.0,
        W - RIGHT + 24.0
    );
    s.push_str("</svg>\n");
    s
}

fn escape(t: &str) -> String {
    t.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

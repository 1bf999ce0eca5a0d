//! The bench's tables and the scaling plot.

use std::fmt::Write;

use super::{ScalingRow, SceneResult};
use crate::pipeline::GateStops;

/// Lines per scene run on the GPU: the most GPU memory it held after any stroke, as the
/// allocator reports it and as the budget counts the mesh's copy; its submissions and
/// blocking read-backs.
/// One line per scene run with `--policy fuse`: what its topology changes did and cost.
pub fn topology_lines(results: &[SceneResult]) -> String {
    let mut out = String::new();
    for r in results {
        let Some(t) = &r.topology else { continue };
        let _ = writeln!(
            out,
            "topology {}: {} joins, {} splits, {} refused ({:.2} joins and {:.2} splits a stroke); {:.1} ms a stroke, {:.1} % of the strokes' time",
            r.name,
            t.joins,
            t.splits,
            t.refused,
            t.joins_per_stroke,
            t.splits_per_stroke,
            t.ms_per_stroke,
            100.0 * t.share
        );
    }
    out
}

pub fn gpu_memory_lines(results: &[SceneResult]) -> String {
    let mib = |bytes: u64| bytes as f64 / (1u64 << 20) as f64;
    let mut out = String::new();
    for r in results {
        let Some(m) = &r.gpu_memory else { continue };
        let held = match (m.allocated_bytes, m.reserved_bytes) {
            (Some(allocated), Some(reserved)) => format!(
                "{:.1} MiB in buffers ({:.1} MiB reserved by the allocator)",
                mib(allocated),
                mib(reserved)
            ),
            _ => "no allocator report from this backend".to_string(),
        };
        let _ = writeln!(
            out,
            "gpu memory {}: at most {held}; the budget counts {:.1} MiB of its {:.0} MiB \
             (SLAYER_GPU_BUDGET_MIB)",
            r.name,
            mib(m.budget_bytes),
            mib(m.budget_limit_bytes)
        );
        if let Some(c) = &r.gpu_calls {
            let feed = c
                .samples_per_call
                .map_or("a stroke".to_string(), |n| format!("{n} samples"));
            let _ = writeln!(
                out,
                "gpu calls {}: {:.2} submissions and {:.2} blocking read-backs per sample \
                 ({:.2} ms submitting, {:.2} ms waiting), {:.2} read-backs per stroke, {:.2} per \
                 call ({feed} per call); {} samples and \
                 {} steps taken from runs ahead ({} samples split in two there), the gate \
                 stopped {} ({:.1}% of samples: {})",
                r.name,
                c.submissions_per_sample,
                c.read_backs_per_sample,
                c.submit_ms_per_sample,
                c.waited_ms_per_sample,
                c.read_backs_per_stroke,
                c.read_backs_per_call,
                c.samples_ahead,
                c.steps_ahead,
                c.split_ahead,
                c.gate_stops,
                100.0 * c.gate_stops_per_sample,
                stop_reasons(&c.gate_stops_by)
            );
        }
    }
    out
}

/// The paper's Table 1 layout, plus our per-sample figures; the paper's rows follow for
/// comparison.
pub fn paper_table(results: &[SceneResult]) -> String {
    let mut out = String::new();
    let _ = writeln!(
        out,
        "{:<9} {:>6} {:>9} {:>9} {:>7} {:>8} {:>8} {:>8} {:>8} {:>8} {:>9} {:>9} {:>9} {:>6}",
        "model",
        "layers",
        "vertices",
        "faces",
        "strokes",
        "select",
        "deform",
        "grid",
        "collide",
        "remesh",
        "ms/sample",
        "ms/stroke",
        "ms/remesh",
        "isect"
    );
    for r in results {
        let total = r.phase_ms.total().max(1e-9);
        let pct = |x: f64| format!("{:.2}%", 100.0 * x / total);
        let _ = writeln!(
            out,
            "{:<9} {:>6} {:>9} {:>9} {:>7} {:>8} {:>8} {:>8} {:>8} {:>8} {:>9.3} {:>9.1} {:>9.1} {:>6}",
            r.name,
            r.layers,
            r.vertices,
            r.faces,
            r.strokes,
            pct(r.phase_ms.selection),
            pct(r.phase_ms.deformation),
            pct(r.phase_ms.grid_update),
            pct(r.phase_ms.collision),
            pct(r.phase_ms.remesh),
            r.ms_per_sample,
            r.ms_per_stroke,
            r.ms_per_remesh,
            r.intersections
        );
    }
    let _ = writeln!(
        out,
        "sLayer paper, Table 1 (i7-6700K, 4 cores; total per brush application):"
    );
    for (model, layers, vertices, faces, strokes, phases, total) in [
        (
            "plaster",
            3,
            "323K",
            "640K",
            279,
            ["4.71%", "0.31%", "1.83%", "66.37%", "8.19%"],
            "110 ms",
        ),
        (
            "bark",
            4,
            "496K",
            "981K",
            6557,
            ["3.66%", "0.30%", "1.26%", "68.13%", "3.98%"],
            "130 ms",
        ),
        (
            "metal",
            3,
            "265K",
            "525K",
            1100,
            ["4.80%", "1.85%", "2.29%", "73.07%", "7.00%"],
            "100 ms",
        ),
    ] {
        let _ = writeln!(
            out,
            "{:<9} {:>6} {:>9} {:>9} {:>7} {:>8} {:>8} {:>8} {:>8} {:>8} {:>9}",
            model,
            layers,
            vertices,
            faces,
            strokes,
            phases[0],
            phases[1],
            phases[2],
            phases[3],
            phases[4],
            total
        );
    }
    out
}

pub fn scaling_table(rows: &[ScalingRow]) -> String {
    let mut out = String::new();
    let base = rows.first().map_or(1.0, |r| r.ms_per_sample.max(1e-9));
    // GPU runs add the most memory the allocator reported in buffers.
    let on_gpu = rows.iter().any(|r| r.gpu_memory.is_some());
    let _ = write!(
        out,
        "{:>10} {:>10} {:>10} {:>12} {:>8} {:>8} {:>9} {:>9} {:>11}",
        "faces",
        "ms/sample",
        "ms/remesh",
        "vs smallest",
        "samples",
        "steps",
        "moves",
        "heap MiB",
        "bytes/face"
    );
    let _ = writeln!(out, "{}", if on_gpu { "   gpu MiB" } else { "" });
    for r in rows {
        let _ = write!(
            out,
            "{:>10} {:>10.3} {:>10.1} {:>11.2}x {:>8} {:>8} {:>9}",
            r.faces,
            r.ms_per_sample,
            r.ms_per_remesh,
            r.ms_per_sample / base,
            r.samples,
            r.steps,
            r.moves
        );
        let _ = match r.peak_heap_bytes {
            Some(bytes) => write!(
                out,
                " {:>9.0} {:>11.0}",
                bytes as f64 / (1u64 << 20) as f64,
                bytes as f64 / r.faces.max(1) as f64
            ),
            None => write!(out, " {:>9} {:>11}", "-", "-"),
        };
        if on_gpu {
            let held = r.gpu_memory.and_then(|m| m.allocated_bytes);
            let _ = match held {
                Some(bytes) => write!(out, " {:>9.1}", bytes as f64 / (1u64 << 20) as f64),
                None => write!(out, " {:>9}", "-"),
            };
        }
        out.push('\n');
    }
    out
}

/// ms per sample against faces (log scale), as a small standalone SVG.
pub fn scaling_svg(rows: &[ScalingRow], title: &str) -> String {
    let (w, h, pad) = (640.0, 400.0, 60.0);
    let max_ms = rows
        .iter()
        .map(|r| r.ms_per_sample.max(r.ms_per_remesh / 10.0))
        .fold(1e-9, f64::max)
        * 1.2;
    let (min_f, max_f) = rows.iter().fold((f64::MAX, 0.0f64), |(lo, hi), r| {
        (lo.min(r.faces as f64), hi.max(r.faces as f64))
    });
    let x = |faces: f64| {
        let span = (max_f.ln() - min_f.ln()).max(1e-9);
        pad + (faces.ln() - min_f.ln()) / span * (w - 2.0 * pad)
    };
    let y = |ms: f64| h - pad - ms / max_ms * (h - 2.0 * pad);
    let mut svg = String::new();
    let _ = writeln!(
        svg,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{w}" height="{h}" font-family="sans-serif" font-size="12">"#
    );
    let _ = writeln!(svg, r#"<rect width="100%" height="100%" fill="white"/>"#);
    let _ = writeln!(
        svg,
        r#"<text x="{}" y="24" text-anchor="middle" font-size="15">{title}</text>"#,
        w / 2.0
    );
    let _ = writeln!(
        svg,
        r#"<line x1="{pad}" y1="{}" x2="{}" y2="{}" stroke="black"/>"#,
        h - pad,
        w - pad,
        h - pad
    );
    let _ = writeln!(
        svg,
        r#"<line x1="{pad}" y1="{pad}" x2="{pad}" y2="{}" stroke="black"/>"#,
        h - pad
    );
    let _ = writeln!(
        svg,
        r#"<text x="{}" y="{}" text-anchor="middle">faces (log scale)</text>"#,
        w / 2.0,
        h - 15.0
    );
    let _ = writeln!(
        svg,
        r#"<text x="18" y="{}" transform="rotate(-90 18 {})" text-anchor="middle">ms per stroke sample</text>"#,
        h / 2.0,
        h / 2.0
    );
    for k in 0..=4 {
        let ms = max_ms * k as f64 / 4.0;
        let _ = writeln!(
            svg,
            r#"<text x="{}" y="{}" text-anchor="end">{ms:.2}</text>"#,
            pad - 6.0,
            y(ms) + 4.0
        );
    }
    let points: Vec<String> = rows
        .iter()
        .map(|r| format!("{:.1},{:.1}", x(r.faces as f64), y(r.ms_per_sample)))
        .collect();
    let _ = writeln!(
        svg,
        r##"<polyline points="{}" fill="none" stroke="#c0392b" stroke-width="2"/>"##,
        points.join(" ")
    );
    for r in rows {
        let (px, py) = (x(r.faces as f64), y(r.ms_per_sample));
        let _ = writeln!(
            svg,
            r##"<circle cx="{px:.1}" cy="{py:.1}" r="4" fill="#c0392b"/>"##
        );
        let _ = writeln!(
            svg,
            r#"<text x="{px:.1}" y="{}" text-anchor="middle">{}K</text>"#,
            h - pad + 16.0,
            r.faces / 1000
        );
    }
    let _ = writeln!(svg, "</svg>");
    svg
}

/// The gate's stops by reason, in words: "2 for several steps, 1 for the selection", or "none".
fn stop_reasons(by: &GateStops) -> String {
    let reasons = [
        (by.several_steps, "for several steps"),
        (by.move_grew, "for a longer move"),
        (by.selection, "for the selection"),
        (by.rings, "for a ring"),
        (by.edges, "for the edges"),
    ];
    let named: Vec<String> = reasons
        .iter()
        .filter(|(count, _)| *count > 0)
        .map(|(count, why)| format!("{count} {why}"))
        .collect();
    if named.is_empty() {
        "none".to_string()
    } else {
        named.join(", ")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stop_reasons_name_each_reason_counted_and_none_without() {
        assert_eq!(stop_reasons(&GateStops::default()), "none");
        let by = GateStops {
            several_steps: 5,
            selection: 2,
            ..GateStops::default()
        };
        assert_eq!(
            stop_reasons(&by),
            "5 for several steps, 2 for the selection"
        );
    }
}

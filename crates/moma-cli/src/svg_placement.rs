//! The figure of `moma place`: the scene's top view (each shape's bounding box), the
//! grasp, the candidate base poses as arrows shaded by score, and the best candidate's
//! support polygon.

use moma::collision::Scene;
use moma::motion::GoalPose;
use moma::motion::placement::Placement;
use moma::stability::SupportPolygon;
use std::fmt::Write;

/// The SVG text.
pub fn render(scene: &Scene, goal: &GoalPose, support: &SupportPolygon, p: &Placement) -> String {
    let g = goal.target.translation.vector;
    // World extent: the scene, the grasp and the searched area.
    let (mut x0, mut y0, mut x1, mut y1) = (p.grid.x0, p.grid.y0, p.grid.x1, p.grid.y1);
    for o in &scene.objects {
        for s in &o.shapes {
            x0 = x0.min(s.aabb.0.x);
            y0 = y0.min(s.aabb.0.y);
            x1 = x1.max(s.aabb.1.x);
            y1 = y1.max(s.aabb.1.y);
        }
    }
    x0 = x0.min(g.x) - 0.3;
    y0 = y0.min(g.y) - 0.3;
    x1 = x1.max(g.x) + 0.3;
    y1 = y1.max(g.y) + 0.3;
    let scale = 600.0 / (x1 - x0).max(y1 - y0);
    let (w, h) = ((x1 - x0) * scale, (y1 - y0) * scale + 30.0);
    let px = |x: f64| (x - x0) * scale;
    let py = |y: f64| (y1 - y) * scale + 30.0;
    let mut svg = format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{w:.0}\" height=\"{h:.0}\" \
         viewBox=\"0 0 {w:.0} {h:.0}\" font-family=\"sans-serif\" font-size=\"12\">\n\
         <rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n"
    );
    let _ = writeln!(
        svg,
        "<text x=\"6\" y=\"18\">base placements for the grasp (top view, world x right, y up): \
         {} of {} poses feasible; best score {}</text>",
        p.counts.feasible,
        p.counts.poses,
        p.candidates
            .first()
            .map_or("-".to_string(), |c| format!("{:.3}", c.score))
    );
    // Searched area.
    let _ = writeln!(
        svg,
        "<rect x=\"{:.1}\" y=\"{:.1}\" width=\"{:.1}\" height=\"{:.1}\" fill=\"none\" \
         stroke=\"#999\" stroke-dasharray=\"4 3\"/>",
        px(p.grid.x0),
        py(p.grid.y1),
        (p.grid.x1 - p.grid.x0) * scale,
        (p.grid.y1 - p.grid.y0) * scale
    );
    for o in &scene.objects {
        for s in &o.shapes {
            let (lo, hi) = s.aabb;
            let _ = writeln!(
                svg,
                "<rect x=\"{:.1}\" y=\"{:.1}\" width=\"{:.1}\" height=\"{:.1}\" fill=\"#bbb\" \
                 fill-opacity=\"0.6\" stroke=\"#666\"><title>{}</title></rect>",
                px(lo.x),
                py(hi.y),
                (hi.x - lo.x) * scale,
                (hi.y - lo.y) * scale,
                o.id
            );
        }
    }
    // Candidates, worst first so the best is drawn on top.
    for (rank, c) in p.candidates.iter().enumerate().rev() {
        let [x, y, th] = c.base;
        let len = 0.12;
        let (ex, ey) = (x + len * th.cos(), y + len * th.sin());
        let shade = (255.0 * (1.0 - c.score.clamp(0.0, 1.0))).round() as u8;
        let (colour, width) = if rank == 0 {
            ("#d62728".to_string(), 3.0)
        } else {
            (format!("rgb({shade},{shade},255)"), 1.5)
        };
        let _ = writeln!(
            svg,
            "<g stroke=\"{colour}\" stroke-width=\"{width}\"><circle cx=\"{:.1}\" cy=\"{:.1}\" \
             r=\"3\" fill=\"{colour}\"/><line x1=\"{:.1}\" y1=\"{:.1}\" x2=\"{:.1}\" y2=\"{:.1}\"/>\
             <title>#{} score {:.3}: m {:.4}, clearance {:.4} m, tip-over margin {:.4} m</title></g>",
            px(x),
            py(y),
            px(x),
            py(y),
            px(ex),
            py(ey),
            rank + 1,
            c.score,
            c.manipulability,
            c.clearance,
            c.tip_over_margin
        );
    }
    // The best candidate's support polygon.
    if let Some(best) = p.candidates.first() {
        let [x, y, th] = best.base;
        let (s, c) = th.sin_cos();
        let pts: Vec<String> = support
            .vertices_xy()
            .iter()
            .map(|v| {
                let (wx, wy) = (x + c * v.x - s * v.y, y + s * v.x + c * v.y);
                format!("{:.1},{:.1}", px(wx), py(wy))
            })
            .collect();
        let _ = writeln!(
            svg,
            "<polygon points=\"{}\" fill=\"#d62728\" fill-opacity=\"0.15\" stroke=\"#d62728\"/>",
            pts.join(" ")
        );
    }
    // The grasp: a cross and its x axis.
    let ax = goal.target.rotation * nalgebra::Vector3::x();
    let _ = writeln!(
        svg,
        "<g stroke=\"#2ca02c\" stroke-width=\"2\"><line x1=\"{:.1}\" y1=\"{:.1}\" x2=\"{:.1}\" \
         y2=\"{:.1}\"/><line x1=\"{:.1}\" y1=\"{:.1}\" x2=\"{:.1}\" y2=\"{:.1}\"/><line \
         x1=\"{:.1}\" y1=\"{:.1}\" x2=\"{:.1}\" y2=\"{:.1}\"/><title>grasp</title></g>",
        px(g.x) - 5.0,
        py(g.y) - 5.0,
        px(g.x) + 5.0,
        py(g.y) + 5.0,
        px(g.x) - 5.0,
        py(g.y) + 5.0,
        px(g.x) + 5.0,
        py(g.y) - 5.0,
        px(g.x),
        py(g.y),
        px(g.x + 0.1 * ax.x),
        py(g.y + 0.1 * ax.y)
    );
    svg.push_str("</svg>\n");
    svg
}

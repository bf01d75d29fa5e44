//! The contact angles along triple curves: where three phases meet, the angle each phase's
//! wedge spans between the two interfaces that bound it (Neumann's triangle fixes them at rest
//! from the three tensions, ARCHITECTURE.md "Surface tension").

use polyphase_tracker::{LabeledMesh, PhaseId};

use crate::junction::junction_edges;

/// The angles (degrees) of the wedges of `phases`, in the order given, where the three meet,
/// averaged along their triple curves by edge length; each interface's direction is fitted
/// over `reach` of it ([`junction_edges`]). `None` where the three do not meet.
pub fn contact_angles(mesh: &LabeledMesh, phases: [PhaseId; 3], reach: f64) -> Option<[f64; 3]> {
    // Interface k lies between the two phases other than phases[k].
    let interface = |k: usize| {
        let (a, b) = (phases[(k + 1) % 3], phases[(k + 2) % 3]);
        (a.min(b), a.max(b))
    };
    let mut sum = [0.0; 3];
    let mut length = 0.0;
    for edge in junction_edges(mesh, reach) {
        let (e1, e2) = edge.along.any_orthonormal_pair();
        let rays: Option<Vec<f64>> = (0..3)
            .map(|k| {
                let (_, nu) = edge.branches.iter().find(|(p, _)| *p == interface(k))?;
                Some(nu.dot(e2).atan2(nu.dot(e1)))
            })
            .collect();
        let Some(rays) = rays else { continue };
        for (k, total) in sum.iter_mut().enumerate() {
            *total += edge.length * wedge(&rays, k);
        }
        length += edge.length;
    }
    (length > 0.0).then(|| sum.map(|s| s / length))
}

/// Angle (degrees) of the wedge of phase `k` between the rays (directions, radians) of the
/// two interfaces other than `k`: the one of their two wedges that the third ray is not in.
fn wedge(rays: &[f64], k: usize) -> f64 {
    let ccw = |from: f64, to: f64| (to - from).rem_euclid(std::f64::consts::TAU);
    let (a, b) = (rays[(k + 1) % 3], rays[(k + 2) % 3]);
    let span = ccw(a, b);
    let angle = if ccw(a, rays[k]) < span {
        std::f64::consts::TAU - span
    } else {
        span
    };
    angle.to_degrees()
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;
    use polyphase_tracker::{GridSpec, MdTree};

    #[test]
    fn three_wedges_fill_the_turn() {
        // Rays at 0°, 100° and 220°: the wedges between them are 100°, 120° and 140°; phase k
        // is opposite ray k.
        let rays = [0.0f64, 100.0, 220.0].map(f64::to_radians);
        let w = [0, 1, 2].map(|k| wedge(&rays, k));
        assert!((w[0] - 120.0).abs() < 1e-9, "{w:?}");
        assert!((w[1] - 140.0).abs() < 1e-9, "{w:?}");
        assert!((w[2] - 100.0).abs() < 1e-9, "{w:?}");
    }

    #[test]
    fn a_contoured_straight_junction_has_its_angles() {
        // Three phases in wedges of 100°, 120° and 140° about a line along z through a slab
        // two cells thick (as slab scenes run), off the grid's nodes: phase k fills the wedge
        // between rays k and k + 1 at 0°, 100°, 220°.
        let h = 0.01;
        let centre = DVec3::new(20.3 * h, 19.6 * h, 0.0);
        let rays = [0.0f64, 100.0, 220.0].map(f64::to_radians);
        let f = move |x: DVec3| {
            let d = (x - centre).truncate();
            let angle = d.y.atan2(d.x).rem_euclid(std::f64::consts::TAU);
            let phase = (0..3)
                .rfind(|&k| angle >= rays[k])
                .expect("the first ray is at 0");
            // The distance to the nearest of the three half-lines.
            let phi = rays
                .iter()
                .map(|&r| {
                    let u = glam::DVec2::new(r.cos(), r.sin());
                    let along = d.dot(u).max(0.0);
                    (d - along * u).length()
                })
                .fold(f64::INFINITY, f64::min);
            (phi, phase as PhaseId)
        };
        let grid = GridSpec {
            origin: DVec3::ZERO,
            h,
            dims: [40, 40, 2],
        };
        let mesh = MdTree::build(&grid, &f).contour(&f);
        let angles = contact_angles(&mesh, [0, 1, 2], 4.0 * h).expect("a triple curve");
        // Straight interfaces: the fit is exact but for the vertices' placement (bisection
        // to a small fraction of a cell); 0.5° is an eighth of the 2°.
        for (got, want) in angles.iter().zip([100.0, 120.0, 140.0]) {
            assert!((got - want).abs() < 0.5, "{angles:?}");
        }
    }
}

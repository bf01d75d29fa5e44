//! Phase volumes under a remeshing operation (issue 12, volume-exact remeshing): how much each
//! phase gains when a patch of triangles is replaced, and where to put a moved vertex so that
//! none gains anything. A phase's volume is the divergence-theorem sum of tetrahedra over its
//! faces, so with the patch's topology fixed it is a linear function of the one moved
//! vertex's position: the positions that keep it are a plane, and those that keep every phase
//! of the patch are the intersection of such planes.

use glam::DVec3;
use nalgebra::{Matrix3, SymmetricEigen, Vector3};
use polyphase_grid::{PhaseId, OUTSIDE};

use super::Tri;
use crate::front::least_squares::constrained_solution;

/// Volume gradients whose quadric eigenvalue is below this fraction of the largest are not
/// restored: two sheets within about 20° of each other (tan²(θ/2) = 0.03) constrain their
/// common vertex too weakly, and restoring both would move it far along their common
/// direction.
const NULL_SPACE: f64 = 0.03;

/// A restoring move longer than this fraction of the operation's length scale is not taken
/// (the operation keeps its plain position and the volume bound then judges it): the linear
/// model is exact, but a long move would reshape the patch.
const MAX_MOVE: f64 = 0.25;

/// The volume each phase (`OUTSIDE` left out) gains when the triangles `old` are replaced by
/// `new` (both bounding the same hole of the rest of the mesh): the tetrahedra sums of
/// [`crate::mesh::LabeledMesh::phase_volumes`] about a common local reference point, whose
/// choice cancels because the two patches share their boundary.
pub(super) fn phase_volume_changes(old: &[Tri], new: &[Tri]) -> Vec<(PhaseId, f64)> {
    let Some(first) = old.first() else {
        return Vec::new();
    };
    let r = first.p[0];
    let mut change: Vec<(PhaseId, f64)> = Vec::new();
    let mut add = |phase: PhaseId, v: f64| {
        if phase == OUTSIDE {
            return;
        }
        match change.iter_mut().find(|(p, _)| *p == phase) {
            Some((_, x)) => *x += v,
            None => change.push((phase, v)),
        }
    };
    for (tris, sign) in [(old, -1.0), (new, 1.0)] {
        for t in tris {
            let [a, b, c] = t.p.map(|p| p - r);
            let v = sign * a.dot(b.cross(c)) / 6.0;
            add(t.labels[1], v);
            add(t.labels[0], -v);
        }
    }
    change
}

/// Largest change of any phase's volume when `old` is replaced by `new`.
pub(super) fn volume_change(old: &[Tri], new: &[Tri]) -> f64 {
    phase_volume_changes(old, new)
        .iter()
        .map(|(_, v)| v.abs())
        .fold(0.0, f64::max)
}

/// The position nearest `p` at which replacing `old` by `new(position)` changes no phase's
/// volume, in the directions the phases' volume gradients constrain (see [`NULL_SPACE`])
/// and within the planes of the domain walls the moved vertex lies on (its `OUTSIDE`
/// faces); `p` itself when that is more than [`MAX_MOVE`] × `scale` away. The gradients are
/// exact differences over `scale`, the volumes being linear in the position.
pub(super) fn volume_preserving(
    old: &[Tri],
    new: &dyn Fn(DVec3) -> Vec<Tri>,
    p: DVec3,
    scale: f64,
) -> DVec3 {
    let star = new(p);
    let walls = wall_projector(&star);
    let at = phase_volume_changes(old, &star);
    let steps =
        [DVec3::X, DVec3::Y, DVec3::Z].map(|e| phase_volume_changes(old, &new(p + scale * e)));
    let mut quadric = Matrix3::<f64>::zeros();
    let mut rhs = Vector3::<f64>::zeros();
    for &(phase, change) in &at {
        let moved = steps
            .each_ref()
            .map(|s| s.iter().find(|(q, _)| *q == phase).map_or(0.0, |(_, v)| *v));
        let g = walls * Vector3::from_fn(|i, _| (moved[i] - change) / scale);
        // A gradient is an area of the star (about scale²); one a billionth of that is
        // rounding (a phase on a wall only, with its one direction projected away).
        if g.norm() <= 1e-9 * scale * scale {
            continue;
        }
        quadric += g * g.transpose();
        rhs -= g * change;
    }
    let d = constrained_solution(quadric, rhs, NULL_SPACE);
    if d.length() <= MAX_MOVE * scale {
        p + d
    } else {
        p
    }
}

/// The orthogonal projection onto the directions along every wall that the star's `OUTSIDE`
/// faces lie on (the identity off the walls, a plane's projector on one wall, a line's along
/// a box edge, zero at a corner).
fn wall_projector(star: &[Tri]) -> Matrix3<f64> {
    let mut normals = Matrix3::<f64>::zeros();
    for t in star.iter().filter(|t| t.labels.contains(&OUTSIDE)) {
        let n = t.area_normal().normalize_or_zero();
        let n = Vector3::new(n.x, n.y, n.z);
        normals += n * n.transpose();
    }
    let eigen = SymmetricEigen::new(normals);
    let largest = eigen.eigenvalues.amax();
    let mut projector = Matrix3::<f64>::identity();
    for k in 0..3 {
        if largest > 0.0 && eigen.eigenvalues[k] > NULL_SPACE * largest {
            let e = eigen.eigenvectors.column(k);
            projector -= e * e.transpose();
        }
    }
    projector
}

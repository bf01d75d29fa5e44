//! Taking the domain box off a contoured starting mesh when no interface reaches it.

use polyphase_grid::{PhaseId, OUTSIDE};

use crate::mesh::LabeledMesh;

/// Removes the domain boundary faces of `mesh` when they form surfaces of their own (no
/// interface meets the boundary and only `background` lies inside it): such faces never move,
/// and at a fine grid spacing they are most of the triangles (90 % for a ball at 32³). Returns
/// the remaining mesh and the volume the removed faces enclosed, which belongs to `background`;
/// otherwise the mesh unchanged and 0.
pub(super) fn detach_box(mesh: LabeledMesh, background: PhaseId) -> (LabeledMesh, f64) {
    let boundary = |l: &[PhaseId; 2]| l.contains(&OUTSIDE);
    let mut used_by_interface = vec![false; mesh.vertices.len()];
    for (t, l) in mesh.triangles.iter().zip(&mesh.labels) {
        if !boundary(l) {
            t.iter().for_each(|&v| used_by_interface[v as usize] = true);
        }
    }
    let detachable = mesh.triangles.iter().zip(&mesh.labels).all(|(t, l)| {
        !boundary(l)
            || (l.contains(&background) && t.iter().all(|&v| !used_by_interface[v as usize]))
    });
    if !detachable || mesh.labels.iter().all(|l| !boundary(l)) {
        return (mesh, 0.0);
    }
    let split = |keep_boundary: bool| {
        let mut index = vec![u32::MAX; mesh.vertices.len()];
        let mut part = LabeledMesh::default();
        for (t, l) in mesh.triangles.iter().zip(&mesh.labels) {
            if boundary(l) != keep_boundary {
                continue;
            }
            let tri = t.map(|v| {
                if index[v as usize] == u32::MAX {
                    index[v as usize] = part.vertices.len() as u32;
                    part.vertices.push(mesh.vertices[v as usize]);
                }
                index[v as usize]
            });
            part.triangles.push(tri);
            part.labels.push(*l);
        }
        part
    };
    let inside = split(true).phase_volumes(background as usize + 1)[background as usize];
    (split(false), inside)
}

#[cfg(test)]
mod tests {
    use glam::DVec3;
    use polyphase_grid::GridSpec;

    use super::*;
    use crate::contour_tracker::ContourTracker;
    use crate::invariants::check;
    use crate::tracker::InterfaceTracker;

    fn ball(centre: DVec3, radius: f64) -> impl Fn(DVec3) -> (f64, PhaseId) {
        move |x| {
            let d = (x - centre).length() - radius;
            (d.abs(), if d < 0.0 { 1 } else { 0 })
        }
    }

    fn contoured(f: impl Fn(DVec3) -> (f64, PhaseId) + Sync) -> LabeledMesh {
        let grid = GridSpec {
            origin: DVec3::ZERO,
            h: 1.0 / 16.0,
            dims: [16; 3],
        };
        ContourTracker::new(grid, &f, 2, 0).0.mesh().clone()
    }

    #[test]
    fn a_ball_inside_the_box_loses_the_box_but_no_volume() {
        let mesh = contoured(ball(DVec3::splat(0.5), 0.25));
        let before = mesh.phase_volumes(2);
        let (ball_only, box_volume) = detach_box(mesh, 0);
        check(&ball_only, 0.0).expect("the ball alone is closed");
        assert!(ball_only.labels.iter().all(|l| !l.contains(&OUTSIDE)));
        let after = ball_only.phase_volumes(2);
        // The ball's faces are untouched, so its volume is the same sum; the unit box encloses
        // exactly 1 (its faces are planar), up to rounding of the divergence-theorem sums.
        assert!((after[1] - before[1]).abs() < 1e-12);
        assert!((box_volume - 1.0).abs() < 1e-12, "{box_volume}");
        assert!((after[0] + box_volume - before[0]).abs() < 1e-12);
    }

    #[test]
    fn a_ball_touching_the_wall_keeps_the_box() {
        let mesh = contoured(ball(DVec3::new(0.5, 0.5, 0.0), 0.3));
        let (kept, box_volume) = detach_box(mesh.clone(), 0);
        assert_eq!(kept, mesh);
        assert_eq!(box_volume, 0.0);
    }
}

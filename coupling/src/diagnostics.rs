//! Measurements of the interface for stats: surge-front position, bubble and spike tips.

use polyphase_tracker::{LabeledMesh, PhaseId};

/// (min, max) along `axis` of the vertices of triangles separating phase `a` from `b`
/// (`b = None`: from any other phase, domain boundary included); `None` when there are none.
/// The surge front of a dam break is the max x of the liquid's surface; the bubble and spike
/// tips of Rayleigh–Taylor are the max and min y of the heavy–light interface.
pub fn interface_extent(
    mesh: &LabeledMesh,
    a: PhaseId,
    b: Option<PhaseId>,
    axis: usize,
) -> Option<(f64, f64)> {
    let mut range: Option<(f64, f64)> = None;
    for (tri, labels) in mesh.triangles.iter().zip(&mesh.labels) {
        let hit = match b {
            Some(b) => *labels == [a, b] || *labels == [b, a],
            None => labels.contains(&a) && labels[0] != labels[1],
        };
        if !hit {
            continue;
        }
        for &v in tri {
            let c = mesh.vertices[v as usize][axis];
            range = Some(match range {
                Some((lo, hi)) => (lo.min(c), hi.max(c)),
                None => (c, c),
            });
        }
    }
    range
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;
    use polyphase_tracker::OUTSIDE;

    #[test]
    fn extent_selects_triangles_by_label_pair() {
        let mesh = LabeledMesh {
            vertices: vec![
                DVec3::new(0.0, 0.0, 0.0),
                DVec3::new(1.0, 0.5, 0.0),
                DVec3::new(0.0, 1.0, 0.0),
                DVec3::new(3.0, -2.0, 0.0),
            ],
            triangles: vec![[0, 1, 2], [0, 3, 2]],
            labels: vec![[1, 0], [1, OUTSIDE]],
        };
        assert_eq!(interface_extent(&mesh, 0, Some(1), 0), Some((0.0, 1.0)));
        assert_eq!(interface_extent(&mesh, 1, None, 1), Some((-2.0, 1.0)));
        assert_eq!(interface_extent(&mesh, 2, None, 1), None);
    }
}

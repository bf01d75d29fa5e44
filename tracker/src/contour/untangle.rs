//! Taking back triple points that tangle the contour: a triple point that
//! [`super::triple_choice`] placed outside the triangle of its face's crossings is returned
//! to the search's point inside it wherever one of its triangles meets another improperly
//! (the front tracker's exact checker), round after round until none does. Inside that
//! triangle no triple line folds (`triple_lines_do_not_fold`), so only the moved points can
//! tangle, and every round takes back at least one.

use glam::DVec3;
use rayon::prelude::*;

use crate::front::broadphase::StaticGrid;
use crate::front::collision::{cell_size_for, swept_triangle_box};
use crate::front::intersection::pair_intersects;
use crate::LabeledMesh;

/// Moves vertex `v` of each `(v, inside)` in `moved` back to `inside` where a triangle at it
/// intersects another.
///
/// The pairs worth testing are found once, from boxes swept between the chosen and the
/// inside positions, so they hold whichever points are taken back; the rounds test only them.
pub(crate) fn take_back_tangles(mesh: &mut LabeledMesh, moved: &[(u32, DVec3)]) {
    if moved.is_empty() {
        return;
    }
    let mut ids: Vec<u32> = moved.iter().map(|m| m.0).collect();
    ids.sort_unstable();
    let mut back = mesh.vertices.clone();
    for &(v, inside) in moved {
        back[v as usize] = inside;
    }
    let pairs = candidate_pairs(mesh, &back, &ids);
    let mut live = ids;
    loop {
        let mut tangled: Vec<u32> = pairs
            .par_iter()
            .filter(|&&(s, t)| pair_intersects(mesh, s, t))
            .flat_map_iter(|&(s, t)| [s, t].into_iter().flat_map(|k| mesh.triangles[k as usize]))
            .filter(|v| live.binary_search(v).is_ok())
            .collect();
        tangled.sort_unstable();
        tangled.dedup();
        if tangled.is_empty() {
            return;
        }
        for &v in &tangled {
            mesh.vertices[v as usize] = back[v as usize];
        }
        live.retain(|v| tangled.binary_search(v).is_err());
    }
}

/// Pairs `(s, t)`, `s < t`, at least one of them at a vertex of `ids`, whose boxes swept
/// from `mesh`'s positions to `back` overlap; sorted.
fn candidate_pairs(mesh: &LabeledMesh, back: &[DVec3], ids: &[u32]) -> Vec<(u32, u32)> {
    let mut marked = vec![false; mesh.vertices.len()];
    for &v in ids {
        marked[v as usize] = true;
    }
    let swept = |t: u32| swept_triangle_box(&mesh.triangles[t as usize], &mesh.vertices, back);
    let near: Vec<u32> = (0..mesh.triangles.len() as u32)
        .into_par_iter()
        .filter(|&t| {
            mesh.triangles[t as usize]
                .iter()
                .any(|&v| marked[v as usize])
        })
        .collect();
    let boxes: Vec<(DVec3, DVec3)> = near.iter().map(|&t| swept(t)).collect();
    let (all_lo, all_hi) = boxes
        .iter()
        .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), b| {
            (lo.min(b.0), hi.max(b.1))
        });
    let cell = cell_size_for(&boxes);
    let grid = StaticGrid::build(boxes, cell);
    let mut pairs: Vec<(u32, u32)> = (0..mesh.triangles.len() as u32)
        .into_par_iter()
        .map_init(Vec::new, |cand, s| {
            let (lo, hi) = swept(s);
            if lo.cmpgt(all_hi).any() || hi.cmplt(all_lo).any() {
                return Vec::new();
            }
            grid.query(lo, hi, cand);
            cand.iter()
                .map(|&i| near[i as usize])
                .filter(|&t| t != s)
                .map(|t| (s.min(t), s.max(t)))
                .collect::<Vec<_>>()
        })
        .flatten()
        .collect();
    pairs.sort_unstable();
    pairs.dedup();
    pairs
}

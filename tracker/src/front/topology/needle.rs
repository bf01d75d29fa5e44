//! Needle edges: edges far shorter than anything the flow or the CCD resolves, left where a
//! junction meets a box edge as two or three vertices a billionth of an edge apart. The
//! remesher's collapse refuses them by its link condition (the thin wedge of a region between
//! them would become coincident triangles), so they stay for the whole run, and the vertices'
//! curvature velocity, whose motion the CCD's near-miss distance cancels, sets the flow's
//! substep (the 64-region foam at 24³ from t = 0.035: 41 substeps a frame). Such an edge is
//! collapsed the way T2 shrinks a region ([`collapse_on_walls`], link condition waived) and
//! the coincident pairs that leaves are resolved as in paper 000 §5.2 (Fig. 14); the collapse
//! is undone unless they all resolve, the end state is intersection-free and the count of
//! regions T2 keeps stays the same (a needle may pinch into pieces below T2's volume, which
//! [`remove_small_regions`] then removes, as T2's own shrinking leaves them).
//!
//! [`remove_small_regions`]: super::vanish::remove_small_regions

use super::degenerate::{coincident_groups, remove_degenerate_pairs};
use super::regions::regions;
use super::vanish::{collapse_on_walls, region_count, WALL_TOLERANCE};
use crate::front::ccd::boxes_overlap;
use crate::front::connectivity::Connectivity;
use crate::front::intersection::pair_intersects;
use crate::front::params::{Bounds, FrontParams};
use crate::front::remesh::{tri_box, Remesher};

/// Edges shorter than this many target lengths are needles: the CCD's near-miss distance
/// ([`crate::front::ccd::NEAR_MISS_REL`] of a pair's extent, about an edge) is 1e-6 L, so a
/// vertex closer than that to its neighbour cannot move past it.
pub const NEEDLE: f64 = 1e-6;

/// Collapses the needle edges of `c`, shortest first; returns how many collapsed. Each
/// collapse moves no wall vertex off its wall, passes the remesher's fold check (as a
/// fail-safe collapse, Appendix A.4) and leaves no intersection ([`intersects_around`]).
pub fn collapse_needles(c: &mut Connectivity, params: &FrontParams, target: f64) -> usize {
    let limit = NEEDLE * target;
    let length = |c: &Connectivity, [a, b]: [u32; 2]| (c.position(a) - c.position(b)).length();
    let needles = |c: &Connectivity| {
        let mut e: Vec<(f64, [u32; 2])> = c
            .edges()
            .into_iter()
            .map(|e| (length(c, e), e))
            .filter(|(l, _)| *l < limit)
            .collect();
        e.sort_by(|x, y| x.0.total_cmp(&y.0).then(x.1.cmp(&y.1)));
        e
    };
    let mut todo = needles(c);
    if todo.is_empty() {
        return 0;
    }
    // Regions T2 keeps ([`remove_small_regions`], which runs next).
    let min_volume = params.min_region_volume * target.powi(3);
    let large = |c: &Connectivity| {
        let all = regions(c);
        let small = all.iter().filter(|r| r.volume < min_volume).count();
        region_count(c, &all) - small
    };
    let count = large(c);
    let mut done = 0;
    // Rounds until one collapses nothing: a collapse can open the way for an edge refused
    // before it. Each removes a vertex, so the rounds end.
    loop {
        let mut round = 0;
        for (_, [a, b]) in todo {
            if c.edge_valence(a, b) == 0 || length(c, [a, b]) >= limit {
                continue;
            }
            let before = c.clone();
            let kept = {
                let mut r = Remesher::new(c, Bounds::new(params, target));
                r.failsafe = true;
                r.coincident = true;
                r.end_state_checked = true;
                collapse_on_walls(&mut r, a, b, WALL_TOLERANCE * target)
            };
            if let Some(keep) = kept {
                remove_degenerate_pairs(c);
                if coincident_groups(c).next().is_none()
                    && !intersects_around(c, keep)
                    && large(c) == count
                {
                    round += 1;
                    continue;
                }
            }
            *c = before;
        }
        done += round;
        todo = needles(c);
        if round == 0 || todo.is_empty() {
            return done;
        }
    }
}

/// Does a live triangle at `v` meet any other live triangle beyond their shared vertices
/// (the exact test of [`pair_intersects`])? Only triangles at `v` moved in a collapse that kept
/// `v`, so this is the collapse's end state checked exactly. The CCD cannot check a needle's
/// pseudo-motion (every pair is within its near-miss distance), and what the mesh must be is
/// intersection-free after the operation; the motion is shorter than the needle, so nothing
/// smaller than that can have been jumped over unseen, and T2 removes regions long before.
fn intersects_around(c: &Connectivity, v: u32) -> bool {
    let at: Vec<u32> = c
        .vertex_triangles(v)
        .iter()
        .copied()
        .filter(|&t| c.is_live(t))
        .collect();
    at.iter().any(|&s| {
        let (lo, hi) = tri_box(c, s);
        (0..c.mesh.triangles.len() as u32).any(|t| {
            t != s && c.is_live(t) && {
                let (tlo, thi) = tri_box(c, t);
                boxes_overlap(lo, hi, tlo, thi) && pair_intersects(&c.mesh, s, t)
            }
        })
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::front::topology::clean;
    use crate::front::topology::vanish::remove_small_regions;
    use crate::mesh::fixtures::lattice_mesh;
    use glam::DVec3;
    use polyphase_grid::PhaseId;

    /// Width of the needle in [`needle`]: a ten-billionth, as the foam's (3e-10 at 24³).
    const WIDTH: f64 = 1e-10;

    /// 4³ box: phase 1 below z = 1/2 and in the cell (0, 0, 2) above it, on the box edge
    /// x = y = 0, with that cell's vertices off the box edge moved to [`WIDTH`] of it: a needle
    /// of phase 1 a cell long standing on its body along the box edge, as a foam's junction
    /// leaves where it meets one. Only x and y move, so every face stays in its plane.
    fn needle() -> Connectivity {
        let mut mesh = lattice_mesh(4, |i, j, k| PhaseId::from(k < 2 || (i, j, k) == (0, 0, 2)));
        for p in &mut mesh.vertices {
            if (p.z == 0.5 || p.z == 0.75) && p.x <= 0.25 && p.y <= 0.25 {
                *p = DVec3::new(p.x.min(WIDTH), p.y.min(WIDTH), p.z);
            }
        }
        Connectivity::new(mesh)
    }

    fn shortest_edge(c: &Connectivity) -> f64 {
        c.edges()
            .into_iter()
            .map(|[a, b]| (c.position(a) - c.position(b)).length())
            .fold(f64::INFINITY, f64::min)
    }

    #[test]
    fn a_needle_along_a_box_edge_collapses_into_the_edge() {
        let mut c = needle();
        clean(&c);
        let target = 0.25;
        assert!(shortest_edge(&c) < NEEDLE * target);
        let volumes = c.mesh.phase_volumes(2);
        let count = regions(&c).len();
        // As the tracker's topology stage: needles, then T2 for the pieces they leave.
        let params = FrontParams::default();
        assert!(collapse_needles(&mut c, &params, target) > 0);
        let min_volume = params.min_region_volume * target.powi(3);
        remove_small_regions(&mut c, &params, target, min_volume);
        c.compact();
        let mesh = clean(&c);
        assert!(
            shortest_edge(&c) >= NEEDLE * target,
            "{}",
            shortest_edge(&c)
        );
        assert_eq!(regions(&c).len(), count);
        // Every vertex moved by less than the needle's width, across faces of area below 1:
        // no phase may change by more than that.
        for (after, before) in mesh.phase_volumes(2).iter().zip(&volumes) {
            assert!((after - before).abs() < 2.0 * WIDTH, "{before} -> {after}");
        }
    }
}

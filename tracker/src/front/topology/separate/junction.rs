//! The collapse that starts a T1 process (paper 000 §5.1.7, Fig. 5): an interface shrinking
//! between two non-manifold curves (e.g. two triple curves) must be collapsed so that they
//! meet in an irregular vertex that vertex separation then resolves. The ordinary collapse
//! pass refuses to merge different non-manifold curves (it would destroy features); here it is
//! allowed, but only where the flow shortens the edge, so that collapse and separation agree
//! and do not undo each other step after step.

use crate::front::connectivity::Connectivity;
use crate::front::params::{Bounds, FrontParams};
use crate::front::remesh::Remesher;

/// Collapses the edges of `c` shorter than the minimum edge length (`params.min_edge *
/// target`) that join two vertices on non-manifold curves (more than two regions around, or a
/// non-manifold edge) while being an ordinary two-triangle edge themselves, when
/// `shrinking(a, b)` says the flow shortens edge `(a, b)` (§5.1.7). Shortest first (ties by
/// index), repeating while that makes progress (at most 4 rounds); each collapse is the
/// remesher's, with its link condition, bounds and CCD check, only the refusal to merge
/// different curves lifted. `shrinking` receives indices of `c` as it is on entry: they stay
/// valid during the call (a collapse keeps one endpoint's index and creates no vertex), so the
/// caller can judge with its own per-vertex data (velocities). Compacts `c` at the end
/// (indices change). Returns the number of collapses.
pub fn collapse_junction_edges(
    c: &mut Connectivity,
    params: &FrontParams,
    target: f64,
    shrinking: &dyn Fn(u32, u32) -> bool,
) -> usize {
    let mut r = Remesher::new(c, Bounds::new(params, target));
    r.junction = true;
    let min_edge = r.b.min_edge;
    let length = |c: &Connectivity, [a, b]: [u32; 2]| (c.position(a) - c.position(b)).length();
    let mut done = 0;
    for _ in 0..4 {
        let mut short: Vec<(f64, [u32; 2])> =
            r.c.edges()
                .into_iter()
                .map(|e| (length(r.c, e), e))
                .filter(|&(l, e)| l < min_edge && is_junction_edge(r.c, e))
                .collect();
        short.sort_by(|x, y| x.0.total_cmp(&y.0).then(x.1.cmp(&y.1)));
        let mut round = 0;
        for (_, e) in short {
            let [a, b] = e;
            if r.c.edge_valence(a, b) > 0
                && length(r.c, e) < min_edge
                && is_junction_edge(r.c, e)
                && shrinking(a, b)
                && r.try_collapse(a, b)
            {
                round += 1;
            }
        }
        done += round;
        if round == 0 {
            break;
        }
    }
    drop(r);
    c.compact();
    done
}

/// Does manifold edge `(a, b)` join two vertices that each lie on a non-manifold curve?
fn is_junction_edge(c: &Connectivity, [a, b]: [u32; 2]) -> bool {
    c.edge_valence(a, b) == 2 && on_curve(c, a) && on_curve(c, b)
}

/// Is `v` on a non-manifold curve: more than two regions around it, or a non-manifold edge?
fn on_curve(c: &Connectivity, v: u32) -> bool {
    c.vertex_regions(v).len() > 2 || c.neighbours(v).iter().any(|&u| c.edge_valence(v, u) != 2)
}

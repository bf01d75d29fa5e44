//! Settling a face's triple point where a crossing has collapsed onto a node (paper 004 §5.2
//! assumes the three interfaces meet inside the face, one crossing per edge).
//!
//! A node lying exactly on an interface (a phase boundary on a lattice plane, as `zalesak`'s
//! two liquids meet at z = 0.5) gives its phase a crossing collapsed onto the node: that phase
//! has no width there, the line search finds no line for it, and its fallback ended next to
//! the node, up to 1.1 h inside `zalesak`'s sphere, the sheets from it denting the liquids
//! (45 % of the first step's wrong points at 128³). For such a face the triple point is chosen
//! among candidates: the search's point kept inside the crossings' triangle, and every crossing
//! found along the face's edges on a lattice of N steps (hidden phases included). The score
//! is, first, how many of the face's phases probes 0.3 h around the candidate miss (a point on
//! the triple curve has all three beside it; the face's area cannot tell it from a point on a
//! sheet a cell away from the curve), then how many lattice points the face's reconstruction
//! (each corner's phase up to its crossings and the triple point) misreads. Candidates must
//! keep every phase's region in the face positively oriented. A choice outside the crossings'
//! triangle can still tangle the tetrahedra beside the face (it did on `zalesak` 64³ after
//! seven steps), so [`super::untangle`] takes such choices back where they do. The same choice
//! for every face whose point lies outside the crossings' triangle (an edge hiding a third
//! phase) gained 0.8 wrong points per 10⁵ on `enright` 64³ but cost 8 times the triple
//! points' time, so other faces keep the search's point.

use std::cell::OnceCell;

use glam::DVec3;
use polyphase_grid::PhaseId;

use super::bisect::{clamp_to_triangle, crossing, MARGIN};
use super::sampler::PhaseSampler;

/// Lattice divisions per face edge for the choice: 3N samples on the edges (hidden crossings
/// wider than a tenth of an edge are found), (N − 1)(N − 2)/2 = 36 more inside for the
/// misread count, each lattice triangle 1/N² of the face.
const N: usize = 10;

/// Probe distance around a candidate, in cells: well inside the face's tetrahedra, and far
/// enough that a point on the triple curve sees all three phases.
const PROBE: f64 = 0.3;

/// How far outside the crossings' triangle a choice may lie and still be moved into it, in
/// cells.
const NEAR_INSIDE: f64 = 0.01;

/// A crossing this close to a node (as an edge parameter) has collapsed onto it: `bisect`
/// clamps crossings to [MARGIN, 1 − MARGIN].
const COLLAPSED: f64 = 2.0 * MARGIN;

/// The corners at the ends of the face's edges as [`Lattice::boundary_crossings`] numbers them.
const EDGE_CORNERS: [[usize; 2]; 3] = [[0, 1], [1, 2], [0, 2]];

/// Where the triple points of faces whose crossing collapsed onto a node go.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TriplePoints {
    /// Chosen by sampling the face ([`settle`]): the phases' volumes right, the triple curve
    /// up to a cell off the lattice plane it lies on. The contouring tracker's choice.
    Sampled,
    /// The line search's point kept inside the crossings' triangle: the triple curve stays on
    /// the plane, the liquids dented up to a cell beside it. The front tracker's start, whose
    /// triple curves flows and tension act on: from sampled points `double_bubble` at 16³
    /// ended 4.1° off Plateau's angle (`tests/plateau.rs`) and `cyclic` split a region
    /// (`tests/topology.rs`).
    Searched,
}

/// The face's triple point: `found` (from [`super::bisect::triple_point`]) kept inside the
/// triangle of the `crossings` (`crossings[k]` on the edge opposite corner k) when no crossing
/// has collapsed onto a node; otherwise the best candidate by sampling (module docs). Also returns the point inside the crossings' triangle when the choice lies
/// outside it, for [`super::untangle`] to take back.
pub(crate) fn settle(
    sampler: &dyn PhaseSampler,
    corners: [DVec3; 3],
    phases: [PhaseId; 3],
    crossings: [DVec3; 3],
    found: DVec3,
    h: f64,
) -> (DVec3, Option<DVec3>) {
    let kept = clamp_to_triangle(found, crossings);
    if !collapsed(corners, crossings) {
        return (kept, None);
    }
    let lattice = Lattice::sample(sampler, corners);
    // Where a corner's phase is only a point of the face (both its crossings collapsed onto
    // it), the face is the other two phases', and their interface crosses the corner's edges
    // at a hidden crossing: those go first, so that they win ties (the face's area cannot tell
    // them from the search's point next to the corner, but a sheet from that point dents the
    // tetrahedra on either side by up to a cell).
    let point_corner = (0..3).find(|&k| {
        [(k + 1) % 3, (k + 2) % 3].iter().all(|&e| {
            let far = corners[3 - k - e];
            let t = (crossings[e] - corners[k]).dot(far - corners[k])
                / (far - corners[k]).length_squared();
            t <= COLLAPSED
        })
    });
    let found_on_edges = lattice.boundary_crossings(sampler, h);
    let (first, rest): (Vec<_>, Vec<_>) =
        found_on_edges.into_iter().partition(|(_, pair, edge)| {
            point_corner.is_some_and(|k| {
                let others = [phases[(k + 1) % 3], phases[(k + 2) % 3]];
                EDGE_CORNERS[*edge].contains(&k)
                    && (*pair == others || *pair == [others[1], others[0]])
            })
        });
    let candidates: Vec<DVec3> = first
        .iter()
        .map(|c| clamp_to_triangle(c.0, corners))
        .chain(std::iter::once(kept))
        .chain(rest.iter().map(|c| clamp_to_triangle(c.0, corners)))
        .collect();
    let normal = (corners[1] - corners[0]).cross(corners[2] - corners[0]);
    let mut best = ((usize::MAX, usize::MAX), kept);
    for &t in &candidates {
        let regions = regions(corners, crossings, t);
        let valid = regions
            .iter()
            .all(|(_, tri)| orientation(*tri, normal) > 0.0);
        if !valid {
            continue;
        }
        let missing = missing_nearby(sampler, t, phases, h);
        if missing > best.0 .0 {
            continue;
        }
        let misread = lattice
            .points(sampler)
            .filter(|(x, chi)| {
                regions
                    .iter()
                    .find(|(_, tri)| contains(*tri, *x, normal))
                    .is_some_and(|(k, _)| phases[*k] != *chi)
            })
            .count();
        if (missing, misread) < best.0 {
            best = ((missing, misread), t);
        }
    }
    // A choice within a hundredth of a cell of the crossings' triangle goes into it: it
    // cannot fold anything there, and [`super::untangle`] then has fewer points to check.
    let t = best.1;
    let inside = clamp_to_triangle(t, crossings);
    if t.distance(inside) <= NEAR_INSIDE * h {
        (inside, None)
    } else {
        (t, Some(kept))
    }
}

/// How many of the face's three phases no probe finds within [`PROBE`]·h of `t` (14 probes:
/// the axis and diagonal directions). A point on the triple curve has all three next to it;
/// the face's area alone cannot tell such a point from one on a sheet a cell away from the
/// curve, whose sheets would cut through the tetrahedra beside the face.
fn missing_nearby(sampler: &dyn PhaseSampler, t: DVec3, phases: [PhaseId; 3], h: f64) -> usize {
    let mut seen = [false; 3];
    for dir in probe_directions() {
        let chi = sampler.sample(t + dir * (PROBE * h)).1;
        for k in 0..3 {
            seen[k] |= phases[k] == chi;
        }
        if seen.iter().all(|&s| s) {
            break;
        }
    }
    seen.iter().filter(|&&s| !s).count()
}

/// Unit axis and diagonal directions.
fn probe_directions() -> impl Iterator<Item = DVec3> {
    let axes = (0..3).flat_map(|a| {
        [-1.0, 1.0].map(move |s| {
            let mut d = DVec3::ZERO;
            d[a] = s;
            d
        })
    });
    let diagonals = (0..8).map(|c| {
        let s = |bit: usize| if c >> bit & 1 == 1 { 1.0 } else { -1.0 };
        DVec3::new(s(0), s(1), s(2)) / 3f64.sqrt()
    });
    axes.chain(diagonals)
}

/// Whether a crossing sits within [`COLLAPSED`] of one of its edge's ends.
fn collapsed(corners: [DVec3; 3], crossings: [DVec3; 3]) -> bool {
    (0..3).any(|k| {
        let (a, b) = (corners[(k + 1) % 3], corners[(k + 2) % 3]);
        let t = (crossings[k] - a).dot(b - a) / (b - a).length_squared();
        !(COLLAPSED..=1.0 - COLLAPSED).contains(&t)
    })
}

/// The six triangles of the face's reconstruction, each with the corner whose phase it holds:
/// corner k's region is P_k, its crossing toward k + 1, the triple point, its crossing toward
/// k + 2, fanned from P_k.
fn regions(corners: [DVec3; 3], crossings: [DVec3; 3], t: DVec3) -> [(usize, [DVec3; 3]); 6] {
    std::array::from_fn(|i| {
        let k = i / 2;
        let toward_next = crossings[(k + 2) % 3];
        let toward_prev = crossings[(k + 1) % 3];
        if i % 2 == 0 {
            (k, [corners[k], toward_next, t])
        } else {
            (k, [corners[k], t, toward_prev])
        }
    })
}

/// Twice the signed area of `tri` along `normal`'s direction (times |normal|).
fn orientation(tri: [DVec3; 3], normal: DVec3) -> f64 {
    (tri[1] - tri[0]).cross(tri[2] - tri[0]).dot(normal)
}

/// Whether `x` (in the face's plane) lies in `tri`, boundary included.
fn contains(tri: [DVec3; 3], x: DVec3, normal: DVec3) -> bool {
    let tol = -1e-12 * normal.length_squared();
    (0..3).all(|k| orientation([tri[k], tri[(k + 1) % 3], x], normal) >= tol)
}

/// The face sampled at the points corners[0] + (u·e1 + v·e2)/N, u + v ≤ N: its three edges
/// at once, its inside only when a score needs it.
struct Lattice {
    corners: [DVec3; 3],
    /// (position, φ, χ) along each edge, as [`EDGE_CORNERS`] orders them, N + 1 points each.
    edges: [Vec<(DVec3, f64, PhaseId)>; 3],
    inside: OnceCell<Vec<(DVec3, PhaseId)>>,
}

impl Lattice {
    fn at(corners: [DVec3; 3], u: usize, v: usize) -> DVec3 {
        let (e1, e2) = (corners[1] - corners[0], corners[2] - corners[0]);
        corners[0] + (e1 * u as f64 + e2 * v as f64) / N as f64
    }

    fn sample(sampler: &dyn PhaseSampler, corners: [DVec3; 3]) -> Self {
        let edge = |uv: &dyn Fn(usize) -> (usize, usize)| -> Vec<(DVec3, f64, PhaseId)> {
            (0..=N)
                .map(|s| {
                    let (u, v) = uv(s);
                    let x = Self::at(corners, u, v);
                    let (phi, chi) = sampler.sample(x);
                    (x, phi, chi)
                })
                .collect()
        };
        Lattice {
            corners,
            edges: [edge(&|s| (s, 0)), edge(&|s| (N - s, s)), edge(&|s| (0, s))],
            inside: OnceCell::new(),
        }
    }

    /// Every lattice point with its phase (edge points shared by two edges come twice).
    fn points<'a>(
        &'a self,
        sampler: &dyn PhaseSampler,
    ) -> impl Iterator<Item = (DVec3, PhaseId)> + 'a {
        let inside = self.inside.get_or_init(|| {
            (1..N)
                .flat_map(|v| (1..N - v).map(move |u| (u, v)))
                .map(|(u, v)| {
                    let x = Self::at(self.corners, u, v);
                    (x, sampler.sample(x).1)
                })
                .collect()
        });
        self.edges
            .iter()
            .flatten()
            .map(|&(x, _, chi)| (x, chi))
            .chain(inside.iter().copied())
    }

    /// Every change of phase between neighbouring lattice points along the face's three
    /// edges, bisected ([`crossing`]), with its two phases and edge; hidden phases wider than
    /// a lattice step included.
    fn boundary_crossings(
        &self,
        sampler: &dyn PhaseSampler,
        h: f64,
    ) -> Vec<(DVec3, [PhaseId; 2], usize)> {
        let mut out = Vec::new();
        for (e, edge) in self.edges.iter().enumerate() {
            for w in edge.windows(2) {
                let (a, b) = (w[0], w[1]);
                if a.2 != b.2 {
                    let x = crossing(sampler, a.0, b.0, (a.1, a.2), (b.1, b.2), h).0;
                    out.push((x, [a.2, b.2], e));
                }
            }
        }
        out
    }
}

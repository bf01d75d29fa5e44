//! The connected regions ("components") of each phase of a labeled mesh, and which component
//! lies on each side of each face: the volume correction keeps each component's volume, so a
//! drop is not fed by another drop of its phase.
//!
//! A phase's boundary is split into pieces: its faces (domain-boundary faces included, so each
//! piece is closed) joined across shared edges when the same phase lies on the joined side. At
//! a non-manifold edge all faces of the phase are joined, so two regions of a phase that touch
//! along an edge count as one. A piece that encloses a positive volume bounds a region from
//! outside; one that encloses none (a cavity: a bubble in a drop) belongs to the smallest
//! region of its phase that holds it (by the winding number of the outer piece at one of its
//! points). A cavity held by no region (a contouring sliver) belongs to no component: the
//! correction leaves its faces' side alone.

use glam::DVec3;
use polyphase_grid::{PhaseId, OUTSIDE};
use rayon::prelude::*;

use crate::mesh::LabeledMesh;

/// No component: the background phase, the domain's outside, or a cavity no region holds.
pub const NONE: u32 = u32::MAX;

/// The components of every corrected phase of one mesh, numbered in the order of their first
/// face in the mesh (so the numbering is a function of the mesh alone).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Components {
    /// Phase of each component.
    pub phase: Vec<PhaseId>,
    /// Volume each component encloses (m³); positive.
    pub volume: Vec<f64>,
    /// Area of each component's interfaces with other phases (domain-boundary faces excluded).
    pub area: Vec<f64>,
    /// Per triangle, the component on its `[front, back]` side ([`NONE`] where there is none).
    pub sides: Vec<[u32; 2]>,
}

impl Components {
    /// The components of every phase `0..n_phases` of `mesh` but `background` (which the
    /// correction holds as its reference and never splits).
    pub fn find(mesh: &LabeledMesh, n_phases: usize, background: PhaseId) -> Components {
        let pieces = Pieces::find(mesh, n_phases, background);
        let owner = pieces.owners(mesh);
        // Components in the order of their outer piece, which is the order of first faces.
        let mut index = vec![NONE; owner.len()];
        let mut found = Components {
            sides: vec![[NONE; 2]; mesh.triangle_count()],
            ..Components::default()
        };
        for (p, &o) in owner.iter().enumerate() {
            if o == p as u32 {
                index[p] = found.phase.len() as u32;
                found.phase.push(pieces.phase[p]);
                found.volume.push(0.0);
                found.area.push(0.0);
            }
        }
        for (p, &o) in owner.iter().enumerate() {
            if o != NONE {
                let c = index[o as usize] as usize;
                found.volume[c] += pieces.volume[p];
                found.area[c] += pieces.area[p];
            }
        }
        for (half, &p) in pieces.of_half.iter().enumerate() {
            if p != NONE && owner[p as usize] != NONE {
                found.sides[half / 2][half % 2] = index[owner[p as usize] as usize];
            }
        }
        found
    }

    /// Number of components.
    pub fn len(&self) -> usize {
        self.phase.len()
    }

    /// Whether there are none.
    pub fn is_empty(&self) -> bool {
        self.phase.is_empty()
    }

    /// Number of components of each phase `0..n_phases`.
    pub fn count_per_phase(&self, n_phases: usize) -> Vec<usize> {
        let mut count = vec![0; n_phases];
        for &p in &self.phase {
            if let Some(c) = count.get_mut(p as usize) {
                *c += 1;
            }
        }
        count
    }

    /// These components with all components of a phase taken as one: the per-phase
    /// correction this module replaced, kept to show what it did.
    #[cfg(test)]
    pub(crate) fn whole_phases(split: Components, n_phases: usize) -> Self {
        let mut index = vec![NONE; n_phases];
        let mut whole = Components {
            sides: split.sides.clone(),
            ..Components::default()
        };
        for c in 0..split.len() {
            let p = split.phase[c] as usize;
            if index[p] == NONE {
                index[p] = whole.phase.len() as u32;
                whole.phase.push(split.phase[c]);
                whole.volume.push(0.0);
                whole.area.push(0.0);
            }
            whole.volume[index[p] as usize] += split.volume[c];
            whole.area[index[p] as usize] += split.area[c];
        }
        for side in whole.sides.iter_mut().flatten() {
            if *side != NONE {
                *side = index[split.phase[*side as usize] as usize];
            }
        }
        whole
    }
}

/// The edge-connected pieces of the phases' boundaries. A half-face `2t + s` is side `s` of
/// triangle `t` (0 front, 1 back).
struct Pieces {
    /// Per half-face, its piece ([`NONE`] for sides no component is sought for).
    of_half: Vec<u32>,
    phase: Vec<PhaseId>,
    /// Enclosed volume: positive for a region's outer boundary, not for a cavity's.
    volume: Vec<f64>,
    area: Vec<f64>,
}

impl Pieces {
    fn find(mesh: &LabeledMesh, n_phases: usize, background: PhaseId) -> Pieces {
        let halves = 2 * mesh.triangle_count();
        let phase_of = |half: usize| {
            let [front, back] = mesh.labels[half / 2];
            let (own, other) = if half % 2 == 1 {
                (back, front)
            } else {
                (front, back)
            };
            (own != OUTSIDE && own != background && (own as usize) < n_phases && own != other)
                .then_some(own)
        };
        // (edge, phase, half-face) for every edge of every half-face sought; sorted, runs of the
        // same edge and phase are joined.
        // Every tuple is distinct (one half-face each), so the parallel unstable sort's order
        // is the one total order.
        let mut edges: Vec<(u32, u32, PhaseId, u32)> = (0..halves)
            .into_par_iter()
            .flat_map_iter(|half| {
                let [a, b, c] = mesh.triangles[half / 2];
                phase_of(half).into_iter().flat_map(move |phase| {
                    [(a, b), (b, c), (c, a)].map(|(x, y)| (x.min(y), x.max(y), phase, half as u32))
                })
            })
            .collect();
        edges.par_sort_unstable();
        let mut parent: Vec<u32> = (0..halves as u32).collect();
        for pair in edges.windows(2) {
            let ((a0, b0, p0, h0), (a1, b1, p1, h1)) = (pair[0], pair[1]);
            if (a0, b0, p0) == (a1, b1, p1) {
                union(&mut parent, h0, h1);
            }
        }
        let centre = mesh.bbox().map_or(DVec3::ZERO, |(lo, hi)| 0.5 * (lo + hi));
        let mut pieces = Pieces {
            of_half: vec![NONE; halves],
            phase: Vec::new(),
            volume: Vec::new(),
            area: Vec::new(),
        };
        let mut of_root = vec![NONE; halves];
        for half in 0..halves {
            let Some(phase) = phase_of(half) else {
                continue;
            };
            let r = root(&mut parent, half as u32) as usize;
            if of_root[r] == NONE {
                of_root[r] = pieces.phase.len() as u32;
                pieces.phase.push(phase);
                pieces.volume.push(0.0);
                pieces.area.push(0.0);
            }
            let p = of_root[r];
            pieces.of_half[half] = p;
            let t = half / 2;
            let [a, b, c] = mesh.corners(t).map(|x| x - centre);
            // The tetrahedron (centre, a, b, c) counts for the back phase, against the front's.
            let sign = if half % 2 == 1 { 1.0 } else { -1.0 };
            pieces.volume[p as usize] += sign * a.dot(b.cross(c)) / 6.0;
            if !mesh.labels[t].contains(&OUTSIDE) {
                pieces.area[p as usize] += mesh.area(t);
            }
        }
        pieces
    }

    /// Per piece, the piece whose region it belongs to: itself for an outer boundary (positive
    /// volume), the smallest outer piece of its phase holding it for a cavity, [`NONE`] for a
    /// cavity none holds.
    fn owners(&self, mesh: &LabeledMesh) -> Vec<u32> {
        let n = self.phase.len();
        let mut halves: Vec<Vec<usize>> = vec![Vec::new(); n];
        for (half, &p) in self.of_half.iter().enumerate() {
            if p != NONE {
                halves[p as usize].push(half);
            }
        }
        let bounds: Vec<(DVec3, DVec3)> = halves
            .iter()
            .map(|list| {
                list.iter()
                    .flat_map(|&h| mesh.corners(h / 2))
                    .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), x| {
                        (lo.min(x), hi.max(x))
                    })
            })
            .collect();
        (0..n)
            .map(|p| {
                if self.volume[p] > 0.0 {
                    return p as u32;
                }
                let Some(&first) = halves[p].first() else {
                    return NONE;
                };
                let [a, b, c] = mesh.corners(first / 2);
                let x = (a + b + c) / 3.0;
                // Smallest first, so the first that holds it is the one, and the large ones
                // (a pool of many faces) are wound around only when no small one holds it.
                let mut around: Vec<usize> = (0..n)
                    .filter(|&q| {
                        self.volume[q] > 0.0
                            && self.phase[q] == self.phase[p]
                            && x.cmpge(bounds[q].0).all()
                            && x.cmple(bounds[q].1).all()
                    })
                    .collect();
                around.sort_by(|&q, &r| self.volume[q].total_cmp(&self.volume[r]).then(q.cmp(&r)));
                around
                    .into_iter()
                    .find(|&q| winding_number(mesh, &halves[q], x) > 0.5)
                    .map_or(NONE, |q| q as u32)
            })
            .collect()
    }
}

/// How many times the closed surface of `halves` (each oriented to face out of its side's
/// phase) winds around `x`: 1 inside, 0 outside (sum of signed solid angles over 4π, by the
/// formula of Van Oosterom and Strackee).
fn winding_number(mesh: &LabeledMesh, halves: &[usize], x: DVec3) -> f64 {
    let total: f64 = halves
        .iter()
        .map(|&half| {
            let [a, b, c] = mesh.corners(half / 2).map(|v| v - x);
            let (la, lb, lc) = (a.length(), b.length(), c.length());
            let omega = 2.0
                * a.dot(b.cross(c))
                    .atan2(la * lb * lc + a.dot(b) * lc + a.dot(c) * lb + b.dot(c) * la);
            // The normal points into the front phase: out of the region for a back side.
            if half % 2 == 1 {
                omega
            } else {
                -omega
            }
        })
        .sum();
    total / (4.0 * std::f64::consts::PI)
}

/// Root of `v` in a union–find forest, halving the path on the way.
pub(crate) fn root(parent: &mut [u32], mut v: u32) -> u32 {
    while parent[v as usize] != v {
        let up = parent[parent[v as usize] as usize];
        parent[v as usize] = up;
        v = up;
    }
    v
}

/// Joins the trees of `a` and `b`, the smaller root becoming the root (so roots do not depend on
/// the order of the joins).
pub(crate) fn union(parent: &mut [u32], a: u32, b: u32) {
    let (ra, rb) = (root(parent, a), root(parent, b));
    if ra != rb {
        parent[ra.max(rb) as usize] = ra.min(rb);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::fixtures::{icosphere, lattice_mesh};

    /// Two balls of phase 1 and one of phase 2 in phase 0: three components, each with its
    /// own ball's volume and area, each face knowing its ball.
    #[test]
    fn separate_balls_are_separate_components() {
        let balls = [
            icosphere(DVec3::new(0.3, 0.5, 0.5), 0.1, 3, 1, 0),
            icosphere(DVec3::new(0.7, 0.5, 0.5), 0.15, 3, 2, 0),
            icosphere(DVec3::new(0.5, 0.5, 0.2), 0.05, 3, 1, 0),
        ];
        let mut mesh = LabeledMesh::default();
        balls.iter().for_each(|b| mesh.append(b));
        let found = Components::find(&mesh, 3, 0);
        assert_eq!(found.phase, vec![1, 2, 1]);
        assert_eq!(found.count_per_phase(3), vec![0, 2, 1]);
        let per_ball = mesh.triangle_count() / 3;
        for (c, ball) in balls.iter().enumerate() {
            let alone = ball.phase_volumes(3)[found.phase[c] as usize];
            // The same tetrahedra about another centre: rounding only.
            assert!((found.volume[c] - alone).abs() < 1e-14, "{c}");
            let faces = c * per_ball..(c + 1) * per_ball;
            let area: f64 = faces.clone().map(|t| mesh.area(t)).sum();
            assert!((found.area[c] - area).abs() < 1e-12 * area);
            assert!(faces
                .into_iter()
                .all(|t| found.sides[t] == [NONE, c as u32]));
        }
        let whole = Components::whole_phases(Components::find(&mesh, 3, 0), 3);
        assert_eq!(whole.phase, vec![1, 2]);
        assert!((whole.volume[0] - found.volume[0] - found.volume[2]).abs() < 1e-15);
        assert_eq!(whole.sides[2 * per_ball], [NONE, 0]);
    }

    /// A ball of phase 1 with a cavity of phase 2 inside it: the cavity's surface belongs to
    /// the ball (one component of phase 1, the cavity's volume taken off), and phase 2 is a
    /// component of its own.
    #[test]
    fn a_cavity_belongs_to_the_region_around_it() {
        let mut mesh = icosphere(DVec3::splat(0.5), 0.3, 3, 1, 0);
        let outer = mesh.triangle_count();
        mesh.append(&icosphere(DVec3::new(0.55, 0.5, 0.5), 0.1, 3, 2, 1));
        let found = Components::find(&mesh, 3, 0);
        assert_eq!(found.phase, vec![1, 2]);
        let volumes = mesh.phase_volumes(3);
        // The same tetrahedra as `phase_volumes`, summed in another grouping: rounding only.
        assert!((found.volume[0] - volumes[1]).abs() < 1e-14);
        assert!((found.volume[1] - volumes[2]).abs() < 1e-14);
        assert_eq!(found.sides[0], [NONE, 0]);
        assert_eq!(found.sides[outer], [0, 1]);
    }

    /// Nested shells, phases 1, 2, 1, 2 from the outside in: each cavity belongs to the
    /// smallest region of its phase around it (the innermost cavity of phase 1 lies inside
    /// both phase-1 balls), so each shell is one component with its own volume.
    #[test]
    fn nested_cavities_belong_to_the_innermost_region() {
        let c = DVec3::splat(0.5);
        let shells = [(0.4, 1, 0), (0.3, 2, 1), (0.2, 1, 2), (0.1, 2, 1)];
        let mut mesh = LabeledMesh::default();
        for (r, inside, outside) in shells {
            mesh.append(&icosphere(c, r, 3, inside, outside));
        }
        let found = Components::find(&mesh, 3, 0);
        assert_eq!(found.phase, vec![1, 2, 1, 2]);
        let ball = |k: usize| {
            let (r, inside, _) = shells[k];
            icosphere(c, r, 3, inside, 0).phase_volumes(3)[inside as usize]
        };
        for k in 0..4 {
            let own = ball(k) - if k < 3 { ball(k + 1) } else { 0.0 };
            // Sums of the same tetrahedra about other centres: rounding only.
            assert!(
                (found.volume[k] - own).abs() < 1e-14,
                "{k}: {:?}",
                found.volume
            );
        }
    }

    /// Three phases in a box (two quadrant columns and the background): each corrected phase
    /// is one component closed by the box walls, and the faces between them name both.
    #[test]
    fn box_regions_are_closed_by_the_walls() {
        let mesh = lattice_mesh(4, |i, j, _| match (i < 2, j < 2) {
            (true, true) => 1,
            (false, true) => 2,
            _ => 0,
        });
        let found = Components::find(&mesh, 3, 0);
        assert_eq!(found.count_per_phase(3), vec![0, 1, 1]);
        for c in 0..2 {
            // A quarter of the unit cube, exact in dyadic arithmetic up to rounding.
            assert!((found.volume[c] - 0.25).abs() < 1e-12, "{:?}", found.volume);
        }
        let between = (0..mesh.triangle_count())
            .find(|&t| mesh.labels[t] == [2, 1])
            .expect("an interface between 1 and 2");
        let (one, two) = (
            found.phase.iter().position(|&p| p == 1),
            found.phase.iter().position(|&p| p == 2),
        );
        assert_eq!(
            found.sides[between],
            [two.unwrap() as u32, one.unwrap() as u32]
        );
    }
}

//! Removal of degenerate zero-volume regions (paper 000 §5.2, Fig. 14): after a collapse or a
//! flip, a shrinking tetrahedral region ends as triangles sharing the same three vertices,
//! consistently labeled around the conceptual region "between" them. The pair is deleted when
//! its two outer labels agree, and otherwise replaced by one triangle separating them.
//!
//! Which label is enclosed follows from stacking (derived here; the paper only states the
//! rule): seen along the normal `n` of the group's first triangle, every triangle of the group
//! separates its back label (below) from its front label (above); a triangle with the opposite
//! winding has its labels swapped in that frame. Triangle `i` lies directly below `j` iff
//! `front_i == back_j`: then `front_i` is the enclosed zero-volume region and the pair acts
//! as one triangle from `back_i` (below) to `front_j` (above). Contracting such adjacent pairs
//! keeps every edge's half-face balance ([`crate::invariants::check`]): the enclosed label
//! enters once from each side and cancels, so the result stays closed and label-consistent.

use polyphase_grid::PhaseId;

use crate::front::connectivity::Connectivity;

/// Resolves every group of live triangles of `c` sharing the same three vertices (two: a
/// pair; more: a stack, handled as a chain of pairs) and returns the number of pairs resolved.
/// Within a group, in the frame of its lowest-index triangle, the first adjacent pair
/// (`front` of the lower equals `back` of the upper, lowest indices first) is contracted:
/// both triangles are deleted when the outer labels are equal, otherwise the lower-index one
/// is kept and relabeled to separate the outer labels and the other deleted. This repeats
/// until at most one triangle remains or no two are adjacent (labels that stack in no order,
/// which a label-consistent intersection-free mesh never has, are left untouched).
/// Deterministic: groups in order of their sorted vertex triple. Vertices left unused stay
/// until [`Connectivity::compact`].
pub fn remove_degenerate_pairs(c: &mut Connectivity) -> usize {
    let groups: Vec<Vec<u32>> = coincident_groups(c).collect();
    let mut resolved = 0;
    for group in groups {
        let reference = c.triangle(group[0]);
        // Each member as (triangle, [front, back] in the reference triangle's frame).
        let mut stack: Vec<(u32, [PhaseId; 2])> = group
            .iter()
            .map(|&t| {
                let [front, back] = c.labels(t);
                if same_winding(reference, c.triangle(t)) {
                    (t, [front, back])
                } else {
                    (t, [back, front])
                }
            })
            .collect();
        while let Some((i, j)) = adjacent_pair(&stack) {
            let (ti, [_, below]) = stack[i];
            let (tj, [above, _]) = stack[j];
            resolved += 1;
            // Remove the higher position first so the lower index stays valid.
            let (first, second) = (i.max(j), i.min(j));
            stack.remove(first);
            stack.remove(second);
            if below == above {
                c.remove_triangle(ti);
                c.remove_triangle(tj);
                continue;
            }
            let (keep, gone) = (ti.min(tj), ti.max(tj));
            c.remove_triangle(gone);
            // `[front, back]` of the kept triangle in its own winding; only labels change, so
            // the incidence lists stay valid.
            c.mesh.labels[keep as usize] = if same_winding(reference, c.triangle(keep)) {
                [above, below]
            } else {
                [below, above]
            };
            stack.push((keep, [above, below]));
            stack.sort_unstable_by_key(|&(t, _)| t);
        }
    }
    resolved
}

/// The groups of two or more live triangles of `c` on the same three vertices, each in slot
/// order, groups in order of their sorted vertex triple (deterministic).
pub(crate) fn coincident_groups(c: &Connectivity) -> impl Iterator<Item = Vec<u32>> {
    let mut keyed: Vec<([u32; 3], u32)> = (0..c.mesh.triangles.len() as u32)
        .filter(|&t| c.is_live(t))
        .map(|t| {
            let mut key = c.triangle(t);
            key.sort_unstable();
            (key, t)
        })
        .collect();
    keyed.sort_unstable();
    let mut groups = Vec::new();
    for group in keyed.chunk_by(|x, y| x.0 == y.0).filter(|g| g.len() > 1) {
        groups.push(group.iter().map(|&(_, t)| t).collect::<Vec<u32>>());
    }
    groups.into_iter()
}

/// The first `(i, j)` (lexicographic in stack position) with `i != j` where triangle `i` lies
/// directly below `j`: `front_i == back_j`.
fn adjacent_pair(stack: &[(u32, [PhaseId; 2])]) -> Option<(usize, usize)> {
    (0..stack.len())
        .flat_map(|i| (0..stack.len()).map(move |j| (i, j)))
        .find(|&(i, j)| i != j && stack[i].1[0] == stack[j].1[1])
}

/// Do two triangles on the same three vertices have the same winding (one is a rotation of
/// the other)?
fn same_winding(a: [u32; 3], b: [u32; 3]) -> bool {
    (0..3).any(|k| [b[k], b[(k + 1) % 3], b[(k + 2) % 3]] == a)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::front::intersection::self_intersections;
    use crate::front::topology::clean;
    use crate::mesh::fixtures::{icosphere, push_oriented};
    use crate::mesh::LabeledMesh;
    use glam::DVec3;

    /// Volumes of phases 0..3 agree to rounding of the tetra sums (unit-size meshes, sums of
    /// a few hundred terms of size <= 1: 1e-12 is far above their rounding).
    fn assert_same_volumes(a: &LabeledMesh, b: &LabeledMesh) {
        let (va, vb) = (a.phase_volumes(3), b.phase_volumes(3));
        for (x, y) in va.iter().zip(&vb) {
            assert!((x - y).abs() < 1e-12, "{va:?} vs {vb:?}");
        }
    }

    /// A level-1 icosphere (phase 1 in phase 0) whose triangle 0 is replaced by a coincident
    /// pair enclosing a zero-volume region of phase 2: the lower one (towards phase 1) keeps
    /// the winding, the upper one is written reversed when `reverse_upper`.
    fn sphere_with_pair(reverse_upper: bool) -> LabeledMesh {
        let mut m = icosphere(DVec3::ZERO, 0.5, 1, 1, 0);
        let [a, b, c] = m.triangles[0];
        assert_eq!(m.labels[0], [0, 1]);
        m.labels[0] = [2, 1];
        if reverse_upper {
            m.triangles.push([a, c, b]);
            m.labels.push([2, 0]);
        } else {
            m.triangles.push([a, b, c]);
            m.labels.push([0, 2]);
        }
        m
    }

    #[test]
    fn pair_between_different_phases_becomes_one_triangle() {
        let original = icosphere(DVec3::ZERO, 0.5, 1, 1, 0);
        for reverse_upper in [false, true] {
            let m = sphere_with_pair(reverse_upper);
            // The pair is consistently labeled but coincident, which the checker reports.
            crate::invariants::check(&m, 0.0).expect("pair is label-consistent");
            assert_eq!(self_intersections(&m).len(), 1);
            let mut c = Connectivity::new(m.clone());
            assert_eq!(remove_degenerate_pairs(&mut c), 1);
            let after = clean(&c);
            assert_eq!(after.triangle_count(), original.triangle_count());
            // The survivor is triangle 0 (lower index), relabeled to separate 0 from 1.
            assert_eq!(c.triangle(0), original.triangles[0]);
            assert_eq!(c.labels(0), [0, 1]);
            assert_same_volumes(&m, &after);
            assert_same_volumes(&original, &after);
            // Nothing left to do.
            assert_eq!(remove_degenerate_pairs(&mut c), 0);
        }
    }

    #[test]
    fn pair_between_equal_phases_is_deleted() {
        // A free pillow: two triangles on new vertices inside the sphere, enclosing a
        // zero-volume region of phase 2 with phase 1 on both sides.
        let original = icosphere(DVec3::ZERO, 0.5, 1, 1, 0);
        let mut m = original.clone();
        let n = m.vertices.len() as u32;
        m.vertices.extend([
            DVec3::new(0.1, 0.0, 0.0),
            DVec3::new(0.0, 0.1, 0.0),
            DVec3::new(0.0, 0.0, 0.1),
        ]);
        m.triangles.extend([[n, n + 1, n + 2], [n, n + 2, n + 1]]);
        m.labels.extend([[2, 1], [2, 1]]);
        crate::invariants::check(&m, 0.0).expect("pillow is closed");
        let mut c = Connectivity::new(m.clone());
        assert_eq!(remove_degenerate_pairs(&mut c), 1);
        let after = clean(&c);
        assert_eq!(
            after, original,
            "pillow and its vertices gone, the rest untouched"
        );
        assert_same_volumes(&m, &after);
    }

    #[test]
    fn stack_of_three_reduces_to_the_separating_triangle() {
        // Sphere triangle 0 (phase 0 above, 1 below) with a zero-volume phase-2 pillow
        // attached under it on the same vertices: stack 1 | 2 | 1 | 0 along the normal.
        let original = icosphere(DVec3::ZERO, 0.5, 1, 1, 0);
        let mut m = original.clone();
        let [a, b, c] = m.triangles[0];
        m.triangles.extend([[a, b, c], [b, a, c]]);
        m.labels.extend([[2, 1], [2, 1]]);
        crate::invariants::check(&m, 0.0).expect("stack is label-consistent");
        assert_eq!(self_intersections(&m).len(), 3);
        let mut c = Connectivity::new(m.clone());
        // The pillow (the adjacent pair of lowest stack position) goes; the sphere triangle
        // stays as it was.
        assert_eq!(remove_degenerate_pairs(&mut c), 1);
        let after = clean(&c);
        assert_eq!(after, original);
        assert_same_volumes(&m, &after);
    }

    #[test]
    fn stack_of_three_with_three_phases_contracts_twice() {
        // Stack 1 | 3 | 2 | 0 on the sphere's triangle 0: two enclosed zero-volume regions.
        let original = icosphere(DVec3::ZERO, 0.5, 1, 1, 0);
        let mut m = original.clone();
        let [a, b, c] = m.triangles[0];
        m.labels[0] = [0, 2];
        m.triangles.extend([[a, c, b], [a, b, c]]);
        // Reversed winding: `[3, 2]` is front 2, back 3 in the frame of triangle 0.
        m.labels.extend([[3, 2], [3, 1]]);
        crate::invariants::check(&m, 0.0).expect("stack is label-consistent");
        let mut c = Connectivity::new(m.clone());
        assert_eq!(remove_degenerate_pairs(&mut c), 2);
        let after = clean(&c);
        assert_eq!(after, original);
        let (v, w) = (m.phase_volumes(4), after.phase_volumes(4));
        for (x, y) in v.iter().zip(&w) {
            // Rounding of the tetra sums (see `assert_same_volumes`).
            assert!((x - y).abs() < 1e-12, "{v:?} vs {w:?}");
        }
    }

    #[test]
    fn collapsed_tetrahedral_region_vanishes() {
        // Fig. 13's last step: a tetrahedron of phase 2 inside the sphere's phase 1 has
        // edge (a, b) collapsed by hand (its two triangles deleted, b renamed a), which
        // leaves faces acd and (b → a)cd coincident, with phase 1 on both outer sides.
        let original = icosphere(DVec3::ZERO, 0.5, 1, 1, 0);
        let mut m = original.clone();
        let n = m.vertices.len() as u32;
        let corners = [DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::Z];
        m.vertices.extend(corners.map(|p| 0.1 * p));
        let inside = DVec3::splat(0.02);
        for tri in [[0, 1, 2], [0, 1, 3], [0, 2, 3], [1, 2, 3]] {
            push_oriented(&mut m, tri.map(|k| n + k), inside, 1, 2);
        }
        crate::invariants::check(&m, 0.0).expect("sphere with a tetrahedron is valid");
        let (a, b) = (n, n + 1);
        let mut c = Connectivity::new(m.clone());
        let mut on_edge = Vec::new();
        c.edge_triangles(a, b, &mut on_edge);
        assert_eq!(on_edge.len(), 2);
        for &t in &on_edge {
            c.remove_triangle(t);
        }
        let t = c.vertex_triangles(b)[0];
        let (tri, labels) = (c.triangle(t), c.labels(t));
        c.remove_triangle(t);
        c.add_triangle(tri.map(|v| if v == b { a } else { v }), labels);
        // The paper's observation: the coincident pair is consistently labeled.
        let mut collapsed = c.clone();
        collapsed.compact();
        crate::invariants::check(&collapsed.mesh, 0.0).expect("collapse keeps labels consistent");
        assert_eq!(remove_degenerate_pairs(&mut c), 1);
        assert_eq!(clean(&c), original);
    }
}

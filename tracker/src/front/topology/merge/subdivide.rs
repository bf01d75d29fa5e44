//! Split-to-match of snap-based merging (paper 000 §6.2, Fig. 18): each side of a proximity
//! pair gets a vertex at its closest point, by splitting an edge there or a triangle into
//! three, unless the point lies near an existing vertex (that vertex is used) or, on a
//! triangle, near one of its edges (that edge is split instead). Splits are checked like the
//! remesher's (quality bounds; a split moves no surface) and, because the other surface is by
//! definition close, the new triangles are also checked against their surroundings.

use glam::DVec3;

use super::proximity::Prim;
use super::Merger;
use crate::front::remesh::{starting_with, Tri};
use polyphase_grid::PhaseId;

impl Merger<'_> {
    /// The simplest primitive to give a vertex at `point` of `p`: an existing vertex, or on a
    /// triangle an edge, whose point is within `near` of `point` and still within the merge
    /// distance of the other side's point `partner`; otherwise `p` itself. Returns it with the
    /// point to place the vertex at.
    pub(crate) fn reduce(&self, p: Prim, point: DVec3, partner: DVec3) -> (Prim, DVec3) {
        let usable =
            |q: DVec3| q.distance(point) < self.near && q.distance(partner) <= self.distance;
        let nearest_vertex = |vs: &[u32]| {
            vs.iter()
                .map(|&v| (self.position(v).distance(point), v))
                .min_by(|x, y| x.0.total_cmp(&y.0).then(x.1.cmp(&y.1)))
                .map(|(_, v)| v)
                .filter(|&v| usable(self.position(v)))
        };
        match p {
            Prim::Vertex(v) => (p, self.position(v)),
            Prim::Edge(e) => match nearest_vertex(&e) {
                Some(v) => (Prim::Vertex(v), self.position(v)),
                None => (p, point),
            },
            Prim::Triangle(_, tri) => {
                if let Some(v) = nearest_vertex(&tri) {
                    return (Prim::Vertex(v), self.position(v));
                }
                let on_edge = (0..3)
                    .map(|k| {
                        let (a, b) = (tri[k], tri[(k + 1) % 3]);
                        let e = Prim::Edge([a.min(b), a.max(b)]);
                        let q = self.closest_to(&e, point);
                        (q.distance(point), e, q)
                    })
                    .min_by(|x, y| x.0.total_cmp(&y.0).then(x.1.cmp(&y.1)))
                    .filter(|&(_, _, q)| usable(q));
                match on_edge {
                    Some((_, e, q)) => self.reduce(e, q, partner),
                    None => (p, point),
                }
            }
        }
    }

    /// A vertex of primitive `p` at `point`: the vertex itself, or one split off there (with
    /// the record that undoes the split). `None` when the split is cancelled.
    pub(crate) fn vertex_at(&mut self, p: Prim, point: DVec3) -> Option<(u32, Option<Split>)> {
        let split = match p {
            Prim::Vertex(v) => return Some((v, None)),
            Prim::Edge([a, b]) => self.split_edge_at(a, b, point)?,
            Prim::Triangle(t, _) => self.split_triangle_at(t, point)?,
        };
        Some((split.vertex, Some(split)))
    }

    /// Undoes `split`, the last edit made near it: its children give way to its parents (the
    /// split vertex is left unused).
    pub(crate) fn undo(&mut self, split: Split) {
        for t in split.children {
            self.r.remove_triangle(t);
        }
        for (t, l) in split.parents {
            self.r.add_triangle(t, l);
        }
    }

    /// Splits edge `(a, b)` at `p` (a point of it): every triangle `[u, v, w]` on the edge
    /// becomes `[u, m, w]` and `[m, v, w]` with its labels (Appendix A.2, at `p` instead of the
    /// midpoint).
    fn split_edge_at(&mut self, a: u32, b: u32, p: DVec3) -> Option<Split> {
        let mut tris = Vec::new();
        self.r.c.edge_triangles(a, b, &mut tris);
        let parents: Vec<([u32; 3], [PhaseId; 2])> = tris
            .iter()
            .map(|&t| {
                let tri = self.r.c.triangle(t);
                let rotated = starting_with(tri, a, b)
                    .or_else(|| starting_with(tri, b, a))
                    .expect("a triangle on an edge contains it");
                (rotated, self.r.c.labels(t))
            })
            .collect();
        let children = |m: u32| -> Vec<([u32; 3], [PhaseId; 2])> {
            parents
                .iter()
                .flat_map(|&([u, v, w], l)| [([u, m, w], l), ([m, v, w], l)])
                .collect()
        };
        self.replace(&tris, parents.clone(), children, p)
    }

    /// Splits triangle `t` into three at `p` (a point inside it), each child with its labels.
    fn split_triangle_at(&mut self, t: u32, p: DVec3) -> Option<Split> {
        let parents = [(self.r.c.triangle(t), self.r.c.labels(t))];
        let children = |m: u32| -> Vec<([u32; 3], [PhaseId; 2])> {
            let ([a, b, c], l) = parents[0];
            vec![([a, b, m], l), ([b, c, m], l), ([c, a, m], l)]
        };
        self.replace(&[t], parents.to_vec(), children, p)
    }

    /// Replaces live triangles `old` (with vertices and labels `parents`) by `children` of a
    /// new vertex at `p`, if the quality bounds allow and the children touch nothing they did
    /// not touch as parts of their parents; otherwise leaves the mesh as it was.
    fn replace(
        &mut self,
        old: &[u32],
        parents: Vec<([u32; 3], [PhaseId; 2])>,
        children: impl Fn(u32) -> Vec<([u32; 3], [PhaseId; 2])>,
        p: DVec3,
    ) -> Option<Split> {
        if old.is_empty() {
            return None;
        }
        let geometry = |tri: [u32; 3], labels: [PhaseId; 2], at: &dyn Fn(u32) -> DVec3| Tri {
            p: tri.map(at),
            labels,
        };
        // The new vertex's index is not known yet; `u32::MAX` stands for it.
        let at = |v: u32| if v == u32::MAX { p } else { self.position(v) };
        let before: Vec<Tri> = parents.iter().map(|&(t, l)| geometry(t, l, &at)).collect();
        let after: Vec<Tri> = children(u32::MAX)
            .into_iter()
            .map(|(t, l)| geometry(t, l, &at))
            .collect();
        if !self.r.bounds_allow(&before, &after) {
            return None;
        }
        let vertex = self.r.add_vertex(p);
        for &t in old {
            self.r.remove_triangle(t);
        }
        let children = children(vertex)
            .into_iter()
            .map(|(t, l)| self.r.add_triangle(t, l))
            .collect();
        let split = Split {
            vertex,
            children,
            parents,
        };
        // A zero-length pseudo-motion of the new vertex: the exact test of its triangles
        // against everything near, which a point rounded off the parent's plane could touch.
        if self.r.pseudo_motion_is_safe(&[vertex], &[p], None) {
            Some(split)
        } else {
            self.undo(split);
            None
        }
    }
}

/// A completed split, kept so that it can be undone when the snap it prepared is cancelled.
pub(crate) struct Split {
    /// The new vertex.
    vertex: u32,
    /// The triangles that replaced the parents.
    children: Vec<u32>,
    /// The replaced triangles' vertices and labels.
    parents: Vec<([u32; 3], [PhaseId; 2])>,
}

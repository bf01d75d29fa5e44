//! Feature detection (paper 000 Appendix A): an edge is a feature edge when it is
//! non-manifold (not exactly two triangles) or its dihedral angle exceeds the threshold (30°);
//! a vertex on one or two feature edges lies on a ridge, on three or more it is a peak.

use glam::DVec3;

use super::{starting_with, Remesher};

/// Feature class of a vertex, ordered by how much the remesher must preserve it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub(super) enum Kind {
    Smooth,
    Ridge,
    Peak,
}

/// A vertex's feature class and what it needs for ridge-constrained smoothing.
#[derive(Clone, Debug)]
pub(super) struct VertexFeatures {
    pub kind: Kind,
    /// On a non-manifold edge, or between more than two regions.
    pub non_manifold: bool,
    /// The other ends of its feature edges.
    pub feature_neighbours: Vec<u32>,
}

impl VertexFeatures {
    /// Collapse priority (Appendix A.2): peaks over ridges over smooth vertices, then
    /// non-manifold over manifold.
    pub fn rank(&self) -> (Kind, bool) {
        (self.kind, self.non_manifold)
    }
}

impl Remesher<'_> {
    /// Unit normals of the two triangles of manifold edge `(a, b)`, the second flipped when
    /// the pair is oriented oppositely (labels swapped), so that they compare directly; `None`
    /// for a non-manifold edge.
    pub(super) fn edge_normals(&self, a: u32, b: u32) -> Option<(DVec3, DVec3)> {
        let mut tris = Vec::with_capacity(4);
        self.c.edge_triangles(a, b, &mut tris);
        let [t1, t2] = tris[..] else {
            return None;
        };
        let n1 = self.tri(t1).area_normal().normalize_or_zero();
        let n2 = self.tri(t2).area_normal().normalize_or_zero();
        let same_direction = starting_with(self.c.triangle(t1), a, b).is_some()
            == starting_with(self.c.triangle(t2), a, b).is_some();
        Some((n1, if same_direction { -n2 } else { n2 }))
    }

    /// Is `(a, b)` a feature edge: non-manifold, or dihedral angle above the threshold?
    pub(super) fn is_feature_edge(&self, a: u32, b: u32) -> bool {
        match self.edge_normals(a, b) {
            None => true,
            Some((n1, n2)) => n1.dot(n2) < self.b.cos_feature,
        }
    }

    /// Feature class of vertex `v`.
    pub(super) fn vertex_features(&self, v: u32) -> VertexFeatures {
        let mut non_manifold = self.c.vertex_regions(v).len() > 2;
        // Each feature neighbour, and whether its edge is non-manifold (a junction edge).
        let mut features = Vec::new();
        for u in self.c.neighbours(v) {
            if self.c.edge_valence(v, u) != 2 {
                non_manifold = true;
                features.push((u, true));
            } else if self.is_feature_edge(v, u) {
                features.push((u, false));
            }
        }
        let junction_only = !self.junction_creases && features.iter().any(|&(_, on)| on);
        let feature_neighbours: Vec<u32> = features
            .into_iter()
            .filter(|&(_, on)| on || !junction_only)
            .map(|(u, _)| u)
            .collect();
        let kind = match feature_neighbours.len() {
            0 => Kind::Smooth,
            1 | 2 => Kind::Ridge,
            _ => Kind::Peak,
        };
        VertexFeatures {
            kind,
            non_manifold,
            feature_neighbours,
        }
    }
}

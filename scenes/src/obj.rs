//! Closed triangle meshes read from OBJ files (tobj): polygons triangulated, equal positions
//! welded across objects and groups, then checked to bound a solid (every edge shared by
//! exactly two faces, consistently oriented, no zero-area face) and turned outward, because
//! inside/outside and signed distance ([`crate::mesh_sdf`]) are only defined for such meshes.

use std::collections::HashMap;

use glam::DVec3;
use thiserror::Error;

/// A closed, consistently and outward oriented triangle mesh.
#[derive(Clone, Debug, PartialEq)]
pub struct ClosedMesh {
    pub vertices: Vec<DVec3>,
    /// Counter-clockwise seen from outside.
    pub triangles: Vec<[u32; 3]>,
}

/// Why an OBJ does not describe a solid; the caller adds the file name.
#[derive(Debug, Error)]
pub enum ObjError {
    #[error("not a valid OBJ file: {0}")]
    Parse(#[from] tobj::LoadError),
    #[error("has no faces")]
    Empty,
    #[error("the vertex {0} is not finite (after scaling)")]
    NotFinite(String),
    #[error(
        "not closed: the edge {a} – {b} belongs to {faces} face(s); every edge must be shared by exactly two faces"
    )]
    Open { a: String, b: String, faces: usize },
    #[error(
        "faces are not consistently oriented: the two faces at the edge {a} – {b} run it in the same direction"
    )]
    Orientation { a: String, b: String },
    #[error("the face {a}, {b}, {c} has zero area")]
    Degenerate { a: String, b: String, c: String },
}

/// Parses OBJ text, maps every position x to `scale`·x + `translate` and checks the result
/// bounds a solid.
pub fn parse_obj(bytes: &[u8], scale: f64, translate: DVec3) -> Result<ClosedMesh, ObjError> {
    let options = tobj::LoadOptions {
        triangulate: true,
        ignore_points: true,
        ignore_lines: true,
        ..Default::default()
    };
    // Materials do not matter for the shape: a referenced .mtl is never opened.
    let (models, _) = tobj::load_obj_buf(&mut &bytes[..], &options, |_| {
        Err(tobj::LoadError::OpenFileFailed)
    })?;
    let mut vertices: Vec<DVec3> = Vec::new();
    let mut welded: HashMap<[u64; 3], u32> = HashMap::new();
    let mut triangles = Vec::new();
    for model in &models {
        let mesh = &model.mesh;
        let mut ids = Vec::with_capacity(mesh.positions.len() / 3);
        for p in mesh.positions.chunks_exact(3) {
            let x = DVec3::new(p[0], p[1], p[2]) * scale + translate;
            if !x.is_finite() {
                return Err(ObjError::NotFinite(format!("{:?}", [p[0], p[1], p[2]])));
            }
            // Equal positions are one vertex, so objects and groups that share a corner close up.
            let key = (x + DVec3::ZERO).to_array().map(f64::to_bits);
            let id = *welded.entry(key).or_insert_with(|| {
                vertices.push(x);
                (vertices.len() - 1) as u32
            });
            ids.push(id);
        }
        for t in mesh.indices.chunks_exact(3) {
            let tri = [0, 1, 2].map(|k| ids.get(t[k] as usize).copied());
            let [Some(a), Some(b), Some(c)] = tri else {
                return Err(ObjError::Parse(tobj::LoadError::FaceVertexOutOfBounds));
            };
            triangles.push([a, b, c]);
        }
    }
    if triangles.is_empty() {
        return Err(ObjError::Empty);
    }
    let mesh = ClosedMesh {
        vertices,
        triangles,
    };
    mesh.check_solid()?;
    Ok(mesh.outward())
}

impl ClosedMesh {
    /// Every edge in exactly two faces, run in opposite directions; every face of positive area.
    fn check_solid(&self) -> Result<(), ObjError> {
        let at = |v: u32| format!("{:?}", self.vertices[v as usize].to_array());
        let (lo, hi) = self.bounds();
        let extent = hi - lo;
        for &[a, b, c] in &self.triangles {
            let [pa, pb, pc] = [a, b, c].map(|v| self.vertices[v as usize]);
            // Twice the area against the bounding box's squared size: below 1e-14 it is rounding.
            if (pb - pa).cross(pc - pa).length() <= 1e-14 * extent.length_squared() {
                return Err(ObjError::Degenerate {
                    a: at(a),
                    b: at(b),
                    c: at(c),
                });
            }
        }
        // Undirected edge → (faces running it a→b with a < b, faces running it b→a).
        let mut edges: HashMap<(u32, u32), (usize, usize)> = HashMap::new();
        for t in &self.triangles {
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                let e = edges.entry((a.min(b), a.max(b))).or_default();
                if a < b {
                    e.0 += 1;
                } else {
                    e.1 += 1;
                }
            }
        }
        // Sorted, so the edge reported is the same on every run.
        let mut list: Vec<_> = edges.into_iter().collect();
        list.sort_unstable();
        for ((a, b), (fwd, back)) in list {
            if fwd + back != 2 {
                return Err(ObjError::Open {
                    a: at(a),
                    b: at(b),
                    faces: fwd + back,
                });
            }
            if fwd != 1 {
                return Err(ObjError::Orientation { a: at(a), b: at(b) });
            }
        }
        Ok(())
    }

    /// The same mesh with faces flipped if they point inward (negative enclosed volume).
    fn outward(mut self) -> Self {
        if self.signed_volume() < 0.0 {
            for t in &mut self.triangles {
                t.swap(1, 2);
            }
        }
        self
    }

    /// Enclosed volume by the divergence theorem (sum of signed tetrahedra to the origin):
    /// positive when the faces point outward.
    pub fn signed_volume(&self) -> f64 {
        self.triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|v| self.vertices[v as usize]);
                a.dot(b.cross(c)) / 6.0
            })
            .sum()
    }

    /// Smallest box holding every vertex.
    pub fn bounds(&self) -> (DVec3, DVec3) {
        self.vertices.iter().fold(
            (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
            |(lo, hi), &v| (lo.min(v), hi.max(v)),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A unit cube as six quads, faces inward when `inward`.
    fn cube(inward: bool) -> String {
        let mut s = String::new();
        for i in 0..8 {
            s += &format!("v {} {} {}\n", i & 1, (i >> 1) & 1, (i >> 2) & 1);
        }
        // Outward (counter-clockwise from outside) quads, 1-based.
        let quads = [
            [1, 3, 4, 2],
            [5, 6, 8, 7],
            [1, 2, 6, 5],
            [3, 7, 8, 4],
            [1, 5, 7, 3],
            [2, 4, 8, 6],
        ];
        for q in quads {
            let q = if inward { [q[3], q[2], q[1], q[0]] } else { q };
            s += &format!("f {} {} {} {}\n", q[0], q[1], q[2], q[3]);
        }
        s
    }

    #[test]
    fn cube_is_closed_and_turned_outward() {
        for inward in [false, true] {
            let m = parse_obj(cube(inward).as_bytes(), 2.0, DVec3::X).unwrap();
            assert_eq!(m.triangles.len(), 12);
            // Scaled by 2: volume 8 exactly (sums of exact small integers).
            assert_eq!(m.signed_volume(), 8.0);
            assert_eq!(m.bounds(), (DVec3::X, DVec3::new(3.0, 2.0, 2.0)));
        }
    }

    #[test]
    fn open_flipped_and_broken_meshes_are_refused() {
        let open: String = cube(false).lines().take(13).collect::<Vec<_>>().join("\n");
        let err = parse_obj(open.as_bytes(), 1.0, DVec3::ZERO).unwrap_err();
        assert!(matches!(err, ObjError::Open { faces: 1, .. }), "{err}");

        let flipped = cube(false).replace("f 1 3 4 2", "f 2 4 3 1");
        let err = parse_obj(flipped.as_bytes(), 1.0, DVec3::ZERO).unwrap_err();
        assert!(matches!(err, ObjError::Orientation { .. }), "{err}");

        let err = parse_obj(b"v 0 0 0\nv 1 0 0\n", 1.0, DVec3::ZERO).unwrap_err();
        assert!(matches!(err, ObjError::Empty), "{err}");

        let err = parse_obj(b"v 0 0 x\nf 1 1 1\n", 1.0, DVec3::ZERO).unwrap_err();
        assert!(matches!(err, ObjError::Parse(_)), "{err}");
    }
}

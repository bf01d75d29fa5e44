//! Binary little-endian PLY for labeled meshes (ARCHITECTURE.md "Output folder":
//! `frames/NNNN.ply`). One fixed layout, written and read exactly: per vertex `double x, y, z`;
//! per face a `uchar`-counted `uint` index list (always 3) and `ushort front, back` labels.

use crate::mesh::LabeledMesh;
use glam::DVec3;
use polyphase_grid::PhaseId;
use std::io::{self, BufWriter, Read, Write};
use thiserror::Error;

/// Header lines before the element counts and between them; other tools depend on this text.
const HEADER_START: [&str; 3] = [
    "ply",
    "format binary_little_endian 1.0",
    "comment polyphase labeled mesh",
];
const VERTEX_PROPS: [&str; 3] = [
    "property double x",
    "property double y",
    "property double z",
];
const FACE_PROPS: [&str; 3] = [
    "property list uchar uint vertex_indices",
    "property ushort front",
    "property ushort back",
];
/// Longest header line accepted, so a binary file cannot make the reader buffer without bound.
const MAX_LINE: usize = 256;
/// Bytes of one face record: count, three indices, two labels.
const FACE_BYTES: usize = 1 + 12 + 4;

/// Why a PLY stream could not be read as a labeled mesh.
#[derive(Debug, Error)]
pub enum PlyError {
    /// The underlying reader failed.
    #[error("PLY read failed: {0}")]
    Io(#[from] io::Error),
    /// A header line differs from the one layout this reader accepts.
    #[error("PLY header line {line}: expected `{expected}`, found `{found}`")]
    Header {
        line: usize,
        expected: String,
        found: String,
    },
    /// The stream ended before the header or the data announced by it.
    #[error("PLY file truncated while reading {what}")]
    Truncated { what: String },
    /// A face lists other than three vertices.
    #[error("PLY face {face} has {count} vertices; only triangles are supported")]
    NotTriangle { face: usize, count: u8 },
    /// A face refers to a vertex beyond the vertex count.
    #[error("PLY face {face} refers to vertex {index}, but there are {vertex_count} vertices")]
    IndexOutOfRange {
        face: usize,
        index: u32,
        vertex_count: usize,
    },
    /// A vertex coordinate is NaN or infinite.
    #[error("PLY vertex {vertex} has a non-finite coordinate {position}")]
    NonFinite { vertex: usize, position: DVec3 },
    /// Bytes follow the last face.
    #[error("PLY file has data after the last face")]
    TrailingData,
}

/// Writes `mesh` as binary little-endian PLY with the fixed header above. Buffered internally;
/// writing to a temporary file and renaming it (atomicity) is the caller's job.
pub fn write_ply<W: Write>(mesh: &LabeledMesh, w: W) -> io::Result<()> {
    let mut w = BufWriter::new(w);
    let [l0, l1, l2] = HEADER_START;
    writeln!(
        w,
        "{l0}\n{l1}\n{l2}\nelement vertex {}",
        mesh.vertices.len()
    )?;
    for line in VERTEX_PROPS {
        writeln!(w, "{line}")?;
    }
    writeln!(w, "element face {}", mesh.triangles.len())?;
    for line in FACE_PROPS {
        writeln!(w, "{line}")?;
    }
    writeln!(w, "end_header")?;
    for v in &mesh.vertices {
        for c in v.to_array() {
            w.write_all(&c.to_le_bytes())?;
        }
    }
    for (tri, labels) in mesh.triangles.iter().zip(&mesh.labels) {
        let mut rec = [0u8; FACE_BYTES];
        rec[0] = 3;
        for (k, i) in tri.iter().enumerate() {
            rec[1 + 4 * k..5 + 4 * k].copy_from_slice(&i.to_le_bytes());
        }
        rec[13..15].copy_from_slice(&labels[0].to_le_bytes());
        rec[15..17].copy_from_slice(&labels[1].to_le_bytes());
        w.write_all(&rec)?;
    }
    w.flush()
}

/// Reads a mesh written by [`write_ply`]. Validates the header line by line, the counts, that
/// every face is a triangle with indices in range, that coordinates are finite and that nothing
/// follows the data. Anything else (ASCII PLY, other properties) is rejected with a clear error.
pub fn read_ply<R: Read>(r: R) -> Result<LabeledMesh, PlyError> {
    let mut r = io::BufReader::new(r);
    let mut line = 0;
    for expected in HEADER_START {
        expect_line(&mut r, expected, &mut line)?;
    }
    let n_vertices = read_count(&mut r, "element vertex", &mut line)?;
    for expected in VERTEX_PROPS {
        expect_line(&mut r, expected, &mut line)?;
    }
    let n_faces = read_count(&mut r, "element face", &mut line)?;
    for expected in FACE_PROPS.iter().chain(&["end_header"]) {
        expect_line(&mut r, expected, &mut line)?;
    }

    let mut vertices = Vec::with_capacity(n_vertices.min(1 << 20));
    let mut buf = [0u8; 24];
    for vertex in 0..n_vertices {
        read_exact(&mut r, &mut buf, "vertices")?;
        let c = |k: usize| {
            let mut b = [0u8; 8];
            b.copy_from_slice(&buf[8 * k..8 * k + 8]);
            f64::from_le_bytes(b)
        };
        let position = DVec3::new(c(0), c(1), c(2));
        if !position.is_finite() {
            return Err(PlyError::NonFinite { vertex, position });
        }
        vertices.push(position);
    }
    let mut triangles = Vec::with_capacity(n_faces.min(1 << 20));
    let mut labels = Vec::with_capacity(n_faces.min(1 << 20));
    let mut rec = [0u8; FACE_BYTES];
    for face in 0..n_faces {
        read_exact(&mut r, &mut rec[..1], "faces")?;
        if rec[0] != 3 {
            return Err(PlyError::NotTriangle {
                face,
                count: rec[0],
            });
        }
        read_exact(&mut r, &mut rec[1..], "faces")?;
        let u32_at = |o: usize| u32::from_le_bytes([rec[o], rec[o + 1], rec[o + 2], rec[o + 3]]);
        let tri = [u32_at(1), u32_at(5), u32_at(9)];
        if let Some(&index) = tri.iter().find(|&&i| i as usize >= n_vertices) {
            return Err(PlyError::IndexOutOfRange {
                face,
                index,
                vertex_count: n_vertices,
            });
        }
        let front = PhaseId::from_le_bytes([rec[13], rec[14]]);
        let back = PhaseId::from_le_bytes([rec[15], rec[16]]);
        triangles.push(tri);
        labels.push([front, back]);
    }
    let mut extra = [0u8; 1];
    if r.read(&mut extra)? != 0 {
        return Err(PlyError::TrailingData);
    }
    Ok(LabeledMesh {
        vertices,
        triangles,
        labels,
    })
}

/// Reads header line `*line + 1`, which must equal `expected`.
fn expect_line<R: Read>(r: &mut R, expected: &str, line: &mut usize) -> Result<(), PlyError> {
    *line += 1;
    let found = read_line(r)?;
    if found == expected {
        Ok(())
    } else {
        Err(PlyError::Header {
            line: *line,
            expected: expected.to_string(),
            found,
        })
    }
}

/// Reads header line `*line + 1`, which must be `<prefix> <count>`.
fn read_count<R: Read>(r: &mut R, prefix: &str, line: &mut usize) -> Result<usize, PlyError> {
    *line += 1;
    let line = *line;
    let found = read_line(r)?;
    found
        .strip_prefix(prefix)
        .and_then(|rest| rest.strip_prefix(' '))
        .filter(|n| !n.is_empty() && n.bytes().all(|b| b.is_ascii_digit()))
        .and_then(|n| n.parse().ok())
        .ok_or_else(|| PlyError::Header {
            line,
            expected: format!("{prefix} <count>"),
            found,
        })
}

/// Reads one `\n`-terminated header line (without the terminator), at most [`MAX_LINE`] bytes.
fn read_line<R: Read>(r: &mut R) -> Result<String, PlyError> {
    let mut bytes = Vec::new();
    let mut b = [0u8; 1];
    loop {
        read_exact(r, &mut b, "header")?;
        if b[0] == b'\n' {
            break;
        }
        bytes.push(b[0]);
        if bytes.len() > MAX_LINE {
            break;
        }
    }
    Ok(String::from_utf8_lossy(&bytes).into_owned())
}

/// `read_exact` that reports end of stream as [`PlyError::Truncated`].
fn read_exact<R: Read>(r: &mut R, buf: &mut [u8], what: &str) -> Result<(), PlyError> {
    r.read_exact(buf).map_err(|e| {
        if e.kind() == io::ErrorKind::UnexpectedEof {
            PlyError::Truncated {
                what: what.to_string(),
            }
        } else {
            PlyError::Io(e)
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::fixtures::{icosphere, lattice_mesh};

    fn sample() -> LabeledMesh {
        let mut m = lattice_mesh(3, |i, j, _| (i + j) as PhaseId);
        m.append(&icosphere(DVec3::new(0.3, -0.7, 0.1), 0.1 + 1e-13, 1, 7, 2));
        m
    }

    fn bytes(m: &LabeledMesh) -> Vec<u8> {
        let mut out = Vec::new();
        write_ply(m, &mut out).unwrap();
        out
    }

    #[test]
    fn round_trip_is_bit_exact() {
        let m = sample();
        let data = bytes(&m);
        let back = read_ply(data.as_slice()).unwrap();
        // PartialEq on f64 vectors: every coordinate identical, not just close.
        assert_eq!(back, m);
        assert_eq!(bytes(&back), data);
        let header = "ply\nformat binary_little_endian 1.0\ncomment polyphase labeled mesh\n";
        assert!(data.starts_with(header.as_bytes()));
        let expected_len = data.len() - 24 * m.vertices.len() - FACE_BYTES * m.triangles.len();
        let text = std::str::from_utf8(&data[..expected_len]).unwrap();
        assert!(
            text.ends_with("property ushort back\nend_header\n"),
            "{text}"
        );
    }

    #[test]
    fn empty_mesh_round_trips() {
        let m = LabeledMesh::default();
        assert_eq!(read_ply(bytes(&m).as_slice()).unwrap(), m);
    }

    #[test]
    fn truncated_file_is_rejected() {
        let data = bytes(&sample());
        for cut in [10, data.len() / 2, data.len() - 1] {
            assert!(matches!(
                read_ply(&data[..cut]),
                Err(PlyError::Truncated { .. })
            ));
        }
        let mut longer = data.clone();
        longer.push(0);
        assert!(matches!(
            read_ply(longer.as_slice()),
            Err(PlyError::TrailingData)
        ));
    }

    #[test]
    fn bad_header_is_rejected() {
        let data = bytes(&sample());
        let ascii = String::from_utf8_lossy(&data).replace("binary_little_endian", "ascii");
        assert!(matches!(
            read_ply(ascii.as_bytes()),
            Err(PlyError::Header { line: 2, .. })
        ));
        let text = String::from_utf8_lossy(&data).replacen("element face ", "element face x", 1);
        assert!(matches!(
            read_ply(text.as_bytes()),
            Err(PlyError::Header { line: 8, .. })
        ));
        assert!(matches!(
            read_ply(&b"solid stl\n"[..]),
            Err(PlyError::Header { line: 1, .. })
        ));
    }

    #[test]
    fn bad_face_data_is_rejected() {
        let m = LabeledMesh {
            vertices: vec![DVec3::ZERO, DVec3::X, DVec3::Y],
            triangles: vec![[0, 1, 2]],
            labels: vec![[0, 1]],
        };
        let mut data = bytes(&m);
        let face = data.len() - FACE_BYTES;
        data[face + 5] = 9;
        let err = read_ply(data.as_slice()).unwrap_err();
        assert!(matches!(
            err,
            PlyError::IndexOutOfRange {
                face: 0,
                index: 9,
                ..
            }
        ));
        assert!(err.to_string().contains("vertex 9"), "{err}");
        data[face + 5] = 1;
        data[face] = 4;
        assert!(matches!(
            read_ply(data.as_slice()),
            Err(PlyError::NotTriangle { count: 4, .. })
        ));
        data[face] = 3;
        let first = face - 72;
        data[first..first + 8].copy_from_slice(&f64::NAN.to_le_bytes());
        assert!(matches!(
            read_ply(data.as_slice()),
            Err(PlyError::NonFinite { vertex: 0, .. })
        ));
    }
}

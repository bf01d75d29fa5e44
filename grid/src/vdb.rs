//! OpenVDB (.vdb) output of grid data, so that φ, χ, velocity and pressure frames open in
//! OpenVDB tools, Houdini and Blender (issue 4 item 3). No Rust crate writes the format,
//! so this writes it from the published layout (file format version 224, OpenVDB's
//! io/Archive, io/Compression and tree node serialisation): header, file metadata, then
//! per grid a descriptor, compression flags, metadata, transform, topology and buffers.
//!
//! Voxel (i, j, k) is cell (i, j, k) of the [`GridSpec`]; the transform is a uniform
//! scale `h` with a translation such that the voxel's index point maps to the cell
//! centre `origin + (i + ½) h`. Trees are the standard 5_4_3 configuration. A voxel is
//! active where its value differs bit for bit from the grid's background; inactive
//! voxels read back as the background, so every cell value survives exactly, and leaves
//! without an active voxel are left out. Output is deterministic: the same input gives
//! the same bytes (the file's UUID is a hash of its contents, not random).

mod fields;
mod meta;
mod stream;
mod tree;

use std::io::Write;
use std::path::Path;

use thiserror::Error;

use crate::GridSpec;
pub use fields::{phase_field_grids, velocity_grid};
use meta::{write_meta, Meta};
use stream::Out;
use tree::{Tree, Voxel};

/// `OPENVDB_MAGIC`, written as a 64-bit integer.
const MAGIC: i64 = 0x5644_4220;
/// File format version written (`OPENVDB_FILE_VERSION` from OpenVDB 4 to 12).
const FILE_VERSION: u32 = 224;
/// Library version recorded in the header: the release the output is tested against.
const LIBRARY_VERSION: (u32, u32) = (10, 0);
/// Per-grid compression flag: store only active values (`COMPRESS_ACTIVE_MASK`).
const COMPRESS_ACTIVE_MASK: u32 = 0x2;
/// Per-grid compression flag: zlib on value arrays (`COMPRESS_ZIP`).
const COMPRESS_ZIP: u32 = 0x1;
/// Byte offset of the UUID in the header (magic, versions, has-offsets flag).
const UUID_AT: usize = 8 + 4 + 4 + 4 + 1;
/// UUID length as OpenVDB stores it: 32 hex digits and 4 hyphens.
const UUID_LEN: usize = 36;

/// What went wrong writing a VDB file.
#[derive(Debug, Error)]
pub enum VdbError {
    /// A grid's value count differs from the grid's cell count.
    #[error("grid '{name}' has {got} values, the grid has {want} cells")]
    Length {
        name: String,
        got: usize,
        want: usize,
    },
    /// An empty or repeated grid name (OpenVDB would rename it on write).
    #[error("grid names must be non-empty and unique; '{0}' is not")]
    Name(String),
    /// A spacing or origin no transform can hold.
    #[error("grid spacing h = {0} must be finite and positive, and the origin finite")]
    Transform(f64),
    /// A dimension or string beyond the format's 32-bit fields.
    #[error("{0} too large for the VDB format")]
    TooLarge(&'static str),
    /// The output could not be written.
    #[error("writing VDB: {0}")]
    Io(#[from] std::io::Error),
}

/// The grid class OpenVDB tools use to interpret values (metadata "class").
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GridClass {
    /// No particular meaning.
    Unknown,
    /// Signed distance, negative inside.
    LevelSet,
    /// Density in \[0, 1\], background 0.
    FogVolume,
}

impl GridClass {
    fn name(self) -> &'static str {
        match self {
            GridClass::Unknown => "unknown",
            GridClass::LevelSet => "level set",
            GridClass::FogVolume => "fog volume",
        }
    }
}

/// How value arrays are stored. Only active values are stored in either case.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Compression {
    /// Raw little-endian values: fastest.
    #[default]
    None,
    /// zlib-compressed values: smaller, slower.
    Zip,
}

/// Cell values of one grid and the background value they are stored against.
#[derive(Clone, Debug)]
pub enum Voxels {
    /// One float per cell (`FloatGrid`).
    Scalar { values: Vec<f32>, background: f32 },
    /// Three floats per cell (`Vec3SGrid`), tagged as a velocity-like vector
    /// ("contravariant relative": transforms like a displacement).
    Vector {
        values: Vec<[f32; 3]>,
        background: [f32; 3],
    },
}

/// One named grid to write; its values are at the cells of the file's [`GridSpec`]
/// (cell `i + nx*(j + ny*k)`).
#[derive(Clone, Debug)]
pub struct VdbGrid {
    /// Grid name as tools show it ("phi", "chi", "v", ...); unique within a file.
    pub name: String,
    /// How tools interpret the values.
    pub class: GridClass,
    /// The values and background.
    pub voxels: Voxels,
}

impl VdbGrid {
    /// A float grid of class [`GridClass::Unknown`].
    pub fn scalar(name: &str, values: Vec<f32>, background: f32) -> Self {
        VdbGrid {
            name: name.to_owned(),
            class: GridClass::Unknown,
            voxels: Voxels::Scalar { values, background },
        }
    }

    /// A 3-vector grid of class [`GridClass::Unknown`].
    pub fn vector(name: &str, values: Vec<[f32; 3]>, background: [f32; 3]) -> Self {
        VdbGrid {
            name: name.to_owned(),
            class: GridClass::Unknown,
            voxels: Voxels::Vector { values, background },
        }
    }

    /// The same grid with another class.
    pub fn with_class(self, class: GridClass) -> Self {
        VdbGrid { class, ..self }
    }

    fn len(&self) -> usize {
        match &self.voxels {
            Voxels::Scalar { values, .. } => values.len(),
            Voxels::Vector { values, .. } => values.len(),
        }
    }
}

/// Writes `grids` on `spec` as a VDB file at `path` (created or truncated; making the
/// write atomic is the caller's concern).
pub fn write_vdb(
    path: &Path,
    spec: &GridSpec,
    grids: &[VdbGrid],
    compression: Compression,
) -> Result<(), VdbError> {
    let bytes = encode(spec, grids, compression)?;
    std::fs::write(path, bytes)?;
    Ok(())
}

/// Writes `grids` on `spec` as VDB bytes to `w`.
pub fn write_to<W: Write>(
    w: &mut W,
    spec: &GridSpec,
    grids: &[VdbGrid],
    compression: Compression,
) -> Result<(), VdbError> {
    w.write_all(&encode(spec, grids, compression)?)?;
    Ok(())
}

/// The VDB file of `grids` on `spec`, in memory (descriptors hold absolute offsets,
/// so the file is assembled before it is written anywhere).
pub fn encode(
    spec: &GridSpec,
    grids: &[VdbGrid],
    compression: Compression,
) -> Result<Vec<u8>, VdbError> {
    check(spec, grids)?;
    // Reserve for every value stored raw; masks and headers are a few percent more.
    let floats: usize = grids
        .iter()
        .map(|g| match g.voxels {
            Voxels::Scalar { .. } => 1,
            Voxels::Vector { .. } => 3,
        })
        .sum();
    let mut out = Out {
        bytes: Vec::with_capacity(4 * floats * spec.cell_count() + 4096),
    };
    out.i64(MAGIC);
    out.u32(FILE_VERSION);
    out.u32(LIBRARY_VERSION.0);
    out.u32(LIBRARY_VERSION.1);
    out.u8(1); // grid descriptors carry offsets
    out.raw(&[b'0'; UUID_LEN]); // filled in below
    write_meta(&mut out, &[("creator", Meta::Str("polyphase"))])?;
    out.i32(grids.len() as i32);
    for grid in grids {
        write_grid(&mut out, spec, grid, compression)?;
    }
    let uuid = uuid(&out.bytes[UUID_AT + UUID_LEN..]);
    out.bytes[UUID_AT..UUID_AT + UUID_LEN].copy_from_slice(uuid.as_bytes());
    Ok(out.bytes)
}

/// Rejects input the format cannot hold or a reader would misread.
fn check(spec: &GridSpec, grids: &[VdbGrid]) -> Result<(), VdbError> {
    if !(spec.h.is_finite() && spec.h > 0.0 && spec.origin.is_finite()) {
        return Err(VdbError::Transform(spec.h));
    }
    if spec.dims.iter().any(|&n| i32::try_from(n).is_err()) {
        return Err(VdbError::TooLarge("grid dimension"));
    }
    for (n, grid) in grids.iter().enumerate() {
        if grid.name.is_empty() || grids[..n].iter().any(|g| g.name == grid.name) {
            return Err(VdbError::Name(grid.name.clone()));
        }
        if grid.len() != spec.cell_count() {
            return Err(VdbError::Length {
                name: grid.name.clone(),
                got: grid.len(),
                want: spec.cell_count(),
            });
        }
    }
    Ok(())
}

/// One grid: descriptor (name, tree type, no instance parent, three offsets patched
/// once known), then compression flags, metadata, transform, topology and buffers.
fn write_grid(
    out: &mut Out,
    spec: &GridSpec,
    grid: &VdbGrid,
    compression: Compression,
) -> Result<(), VdbError> {
    let (tree, tree_type, vector) = match &grid.voxels {
        Voxels::Scalar { values, background } => (
            Tree::build(spec.dims, values, *background),
            f32::TREE_TYPE,
            false,
        ),
        Voxels::Vector { values, background } => (
            Tree::build(spec.dims, values, *background),
            <[f32; 3]>::TREE_TYPE,
            true,
        ),
    };
    out.string(&grid.name)?;
    out.string(tree_type)?;
    out.string("")?;
    let offsets_at = out.pos();
    out.raw(&[0; 24]);
    let grid_pos = out.pos();

    let flags = COMPRESS_ACTIVE_MASK
        | match compression {
            Compression::None => 0,
            Compression::Zip => COMPRESS_ZIP,
        };
    out.u32(flags);

    // What OpenVDB's own writer records: class, name, vector type, and the statistics
    // tools show without loading the tree (active bounding box and voxel count).
    let mut meta = vec![
        ("class", Meta::Str(grid.class.name())),
        ("name", Meta::Str(&grid.name)),
    ];
    if vector {
        meta.push(("vector_type", Meta::Str("contravariant relative")));
    }
    if let Some((lo, hi)) = tree.active_bbox {
        meta.push(("file_bbox_min", Meta::Vec3i(lo.map(|c| c as i32))));
        meta.push(("file_bbox_max", Meta::Vec3i(hi.map(|c| c as i32))));
    }
    meta.push(("file_voxel_count", Meta::I64(tree.active_count as i64)));
    write_meta(out, &meta)?;

    write_transform(out, spec)?;
    tree.write_topology(out, compression)?;
    let block_pos = out.pos();
    tree.write_buffers(out, compression)?;
    let end_pos = out.pos();
    out.patch_i64(offsets_at, grid_pos as i64);
    out.patch_i64(offsets_at + 8, block_pos as i64);
    out.patch_i64(offsets_at + 16, end_pos as i64);
    Ok(())
}

/// "UniformScaleTranslateMap": world = h · index + (origin + ½h), stored with the
/// derived vectors OpenVDB keeps (voxel size, 1/h, 1/h², 1/(2h)).
fn write_transform(out: &mut Out, spec: &GridSpec) -> Result<(), VdbError> {
    let h = spec.h;
    let t = spec.origin + glam::DVec3::splat(0.5 * h);
    out.string("UniformScaleTranslateMap")?;
    for v in [
        [t.x, t.y, t.z],
        [h; 3],
        [h; 3],
        [1.0 / h; 3],
        [1.0 / (h * h); 3],
        [0.5 / h; 3],
    ] {
        for c in v {
            out.f64(c);
        }
    }
    Ok(())
}

/// A UUID-shaped tag (8-4-4-4-12 hex digits) derived from the file contents, so equal
/// files are byte-identical (OpenVDB only compares tags for equality).
fn uuid(body: &[u8]) -> String {
    // Two FNV-1a-style states over 8-byte words (a tag, not a cryptographic hash),
    // with a final xorshift so that every input bit reaches the printed digits.
    let mut h = [0xcbf2_9ce4_8422_2325u64, 0x6c62_272e_07bb_0142];
    let mut mix = |w: u64| {
        h[0] = (h[0] ^ w).wrapping_mul(0x0000_0100_0000_01b3);
        h[1] = (h[1] ^ w.rotate_left(32)).wrapping_mul(0x9e37_79b9_7f4a_7c15);
    };
    let words = body.chunks_exact(8);
    let tail = words.remainder();
    for w in words {
        mix(u64::from_le_bytes(w.try_into().expect("8-byte chunk")));
    }
    let mut last = [0u8; 8];
    last[..tail.len()].copy_from_slice(tail);
    mix(u64::from_le_bytes(last));
    mix(body.len() as u64);
    let h = h.map(|x| x ^ (x >> 31));
    let hex = format!("{:016x}{:016x}", h[0], h[1]);
    format!(
        "{}-{}-{}-{}-{}",
        &hex[0..8],
        &hex[8..12],
        &hex[12..16],
        &hex[16..20],
        &hex[20..32]
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;

    fn spec() -> GridSpec {
        GridSpec {
            origin: DVec3::new(-1.0, 0.5, 2.0),
            h: 0.25,
            dims: [3, 2, 2],
        }
    }

    #[test]
    fn header_fields_and_deterministic_uuid() {
        let g = VdbGrid::scalar("a", (0..12).map(|i| i as f32).collect(), 0.0);
        let a = encode(&spec(), std::slice::from_ref(&g), Compression::None).unwrap();
        let b = encode(&spec(), &[g], Compression::None).unwrap();
        assert_eq!(a, b);
        assert_eq!(&a[0..8], &MAGIC.to_le_bytes());
        assert_eq!(&a[8..12], &224u32.to_le_bytes());
        let tag = std::str::from_utf8(&a[UUID_AT..UUID_AT + UUID_LEN]).unwrap();
        assert_eq!(tag.matches('-').count(), 4);
        let mut values: Vec<f32> = (0..12).map(|i| i as f32).collect();
        values[11] = 11.5;
        let c = encode(
            &spec(),
            &[VdbGrid::scalar("a", values, 0.0)],
            Compression::None,
        )
        .unwrap();
        assert_ne!(&c[UUID_AT..UUID_AT + UUID_LEN], tag.as_bytes());
    }

    #[test]
    fn bad_input_is_rejected() {
        let g = VdbGrid::scalar("a", vec![0.0; 11], 0.0);
        assert!(matches!(
            encode(&spec(), &[g], Compression::None),
            Err(VdbError::Length {
                got: 11,
                want: 12,
                ..
            })
        ));
        let g = VdbGrid::scalar("a", vec![0.0; 12], 0.0);
        assert!(matches!(
            encode(&spec(), &[g.clone(), g], Compression::None),
            Err(VdbError::Name(_))
        ));
        let mut s = spec();
        s.h = 0.0;
        assert!(matches!(
            encode(&s, &[], Compression::None),
            Err(VdbError::Transform(_))
        ));
    }
}

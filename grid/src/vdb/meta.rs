//! OpenVDB metadata maps (file and grid level): a count, then per item its name, its
//! type name and its value prefixed by the value's byte size (OpenVDB's MetaMap).

use super::stream::Out;
use super::VdbError;

/// A metadata value of one of the types this writer uses.
pub(super) enum Meta<'a> {
    /// "string": the bytes, no terminator.
    Str(&'a str),
    /// "vec3i": three `i32`.
    Vec3i([i32; 3]),
    /// "int64".
    I64(i64),
}

/// Writes the map of `items` in the given order.
pub(super) fn write_meta(out: &mut Out, items: &[(&str, Meta)]) -> Result<(), VdbError> {
    out.u32(items.len() as u32);
    for (name, value) in items {
        out.string(name)?;
        match value {
            Meta::Str(s) => {
                out.string("string")?;
                out.string(s)?;
            }
            Meta::Vec3i(v) => {
                out.string("vec3i")?;
                out.u32(12);
                for c in v {
                    out.i32(*c);
                }
            }
            Meta::I64(v) => {
                out.string("int64")?;
                out.u32(8);
                out.i64(*v);
            }
        }
    }
    Ok(())
}

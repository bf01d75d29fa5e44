//! `frames/NNNN.exr` of a slab scene (issue 18): one pixel per cell of the [`SlabFrame`]'s
//! layer, channels `chi` (phase id, uint), `phi` (m), `velocity.u`, `velocity.v` (m/s) and, in
//! coupled runs, `pressure` (Pa), ZIP-compressed scan lines. The header carries the domain:
//! `origin` (v3d, the layer's lower corner), `cellSize` (double) and, for people, a `comments`
//! line with the extent, the phase names and the frame time.

use anyhow::{Context, Result};
use exr::prelude::{
    AnyChannel, AnyChannels, AttributeValue, Encoding, FlatSamples, Image, Layer, LayerAttributes,
    SmallVec, Text, Vec2, WritableImage,
};
use std::io::Cursor;

use crate::slab::SlabFrame;

/// The EXR bytes of `frame` at time `time` (s); `names` are the phase names by id. Rows run
/// top to bottom as images do: row `r` holds the cells of row `j = ny − 1 − r`.
pub fn encode(frame: &SlabFrame, names: &[String], time: f64) -> Result<Vec<u8>> {
    let [nx, ny, _] = frame.field.grid.dims;
    let mut channels: SmallVec<[AnyChannel<FlatSamples>; 4]> = SmallVec::new();
    channels.push(AnyChannel::new(
        "chi",
        FlatSamples::U32(top_down(nx, ny, |c| u32::from(frame.field.chi[c]))),
    ));
    channels.push(AnyChannel::new(
        "phi",
        FlatSamples::F32(top_down(nx, ny, |c| frame.field.phi[c] as f32)),
    ));
    channels.push(AnyChannel::new(
        "velocity.u",
        FlatSamples::F32(top_down(nx, ny, |c| frame.velocity[c][0])),
    ));
    channels.push(AnyChannel::new(
        "velocity.v",
        FlatSamples::F32(top_down(nx, ny, |c| frame.velocity[c][1])),
    ));
    if let Some(p) = &frame.pressure {
        channels.push(AnyChannel::new(
            "pressure",
            FlatSamples::F32(top_down(nx, ny, |c| p[c])),
        ));
    }
    // One custom attribute in the layer's table and one in the image's: each is a HashMap,
    // and a single entry per map keeps the header's byte order fixed (deterministic files).
    let g = &frame.field.grid;
    let mut attributes = LayerAttributes::default();
    let origin: Vec<u8> = g
        .origin
        .to_array()
        .iter()
        .flat_map(|c| c.to_le_bytes())
        .collect();
    attributes.other.insert(
        Text::from("origin"),
        AttributeValue::Custom {
            kind: Text::from("v3d"),
            bytes: SmallVec::from_vec(origin),
        },
    );
    let phases: Vec<String> = names
        .iter()
        .enumerate()
        .map(|(id, name)| format!("{id} {}", ascii(name)))
        .collect();
    let extent = g.upper() - g.origin;
    let comments = format!(
        "polyphase slab frame, t = {time} s; chi: phase id ({}); phi: distance to the nearest \
         interface (m); velocity.u/v (m/s){}; pixel (i, r) is the cell centred at origin + \
         cellSize (i + 1/2, {ny} - r - 1/2, 1/2); extent {} x {} m",
        phases.join(", "),
        if frame.pressure.is_some() {
            "; pressure (Pa)"
        } else {
            ""
        },
        extent.x,
        extent.y,
    );
    attributes.comments = Some(Text::from(comments.as_str()));
    let layer = Layer::new(
        Vec2(nx, ny),
        attributes,
        Encoding::SMALL_LOSSLESS,
        AnyChannels::sort(channels),
    );
    let mut image = Image::from_layer(layer);
    image
        .attributes
        .other
        .insert(Text::from("cellSize"), AttributeValue::F64(g.h));
    let mut bytes = Cursor::new(Vec::new());
    image
        .write()
        .non_parallel()
        .to_buffered(&mut bytes)
        .context("encoding the EXR frame")?;
    Ok(bytes.into_inner())
}

/// `value(c)` for every cell `c` of an `nx` × `ny` layer, rows from the top (largest y) down.
fn top_down<T>(nx: usize, ny: usize, value: impl Fn(usize) -> T) -> Vec<T> {
    (0..ny)
        .rev()
        .flat_map(|j| (0..nx).map(move |i| i + nx * j))
        .map(value)
        .collect()
}

/// `name` with every non-ASCII character written as `\u{..}`: EXR header text is bytes, and
/// ASCII reads the same in every reader.
fn ascii(name: &str) -> String {
    name.chars()
        .map(|c| match c.is_ascii() {
            true => c.to_string(),
            false => c.escape_unicode().to_string(),
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::ascii;

    #[test]
    fn phase_names_become_ascii_without_losing_characters() {
        assert_eq!(ascii("oil_2"), "oil_2");
        assert_eq!(ascii("eau salée"), "eau sal\\u{e9}e");
    }
}

//! `frames/NNNN.png` of a slab scene (issue 18): each cell of a layer painted in its phase's
//! scene colour (linear RGB, encoded as 8-bit sRGB), one pixel per cell, y upwards, so the
//! 2D figures need no renderer.

use anyhow::{Context, Result};
use polyphase_grid::PhaseId;

/// The PNG bytes of an `nx` × `ny` layer of phase ids `chi` (cell order, x fastest, y up),
/// each phase in `colors[id]`; an id without a colour (none should occur) is drawn black.
pub fn encode(nx: usize, ny: usize, chi: &[PhaseId], colors: &[[f64; 3]]) -> Result<Vec<u8>> {
    let palette: Vec<[u8; 3]> = colors.iter().map(|c| c.map(srgb_byte)).collect();
    let mut rgb = Vec::with_capacity(3 * nx * ny);
    for j in (0..ny).rev() {
        for &phase in &chi[nx * j..nx * (j + 1)] {
            rgb.extend(palette.get(usize::from(phase)).unwrap_or(&[0; 3]));
        }
    }
    let (width, height) = (
        u32::try_from(nx).context("image too wide for a PNG")?,
        u32::try_from(ny).context("image too tall for a PNG")?,
    );
    let mut bytes = Vec::new();
    let mut encoder = png::Encoder::new(&mut bytes, width, height);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    encoder.set_source_srgb(png::SrgbRenderingIntent::Perceptual);
    let mut writer = encoder.write_header().context("encoding the PNG frame")?;
    writer
        .write_image_data(&rgb)
        .context("encoding the PNG frame")?;
    writer.finish().context("encoding the PNG frame")?;
    Ok(bytes)
}

/// A linear colour component in [0, 1] as an 8-bit sRGB value (IEC 61966-2-1 transfer curve).
fn srgb_byte(linear: f64) -> u8 {
    let c = linear.clamp(0.0, 1.0);
    let encoded = if c <= 0.003_130_8 {
        12.92 * c
    } else {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    };
    (encoded * 255.0).round() as u8
}

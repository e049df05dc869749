//! Writing frames: 8-bit sRGB PNG of the colour, 32-bit OpenEXR of the AOVs.

use crate::trace::integrator::Frame;

/// 8-bit sRGB of a linear value (clamped).
#[must_use]
pub fn to_srgb8(v: f32) -> u8 {
    let v = v.clamp(0.0, 1.0);
    let s = if v <= 0.003_130_8 {
        12.92 * v
    } else {
        1.055 * v.powf(1.0 / 2.4) - 0.055
    };
    (s * 255.0 + 0.5) as u8
}

/// Writes RGB8 pixels as a PNG.
///
/// # Errors
/// When the file cannot be written.
pub fn write_png(
    path: &std::path::Path,
    width: usize,
    height: usize,
    rgb: &[u8],
) -> std::io::Result<()> {
    let file = std::fs::File::create(path)?;
    let mut encoder = png::Encoder::new(std::io::BufWriter::new(file), width as u32, height as u32);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    let mut writer = encoder.write_header().map_err(std::io::Error::other)?;
    writer
        .write_image_data(rgb)
        .map_err(std::io::Error::other)?;
    writer.finish().map_err(std::io::Error::other)
}

impl Frame {
    /// The frame as 8-bit sRGB.
    #[must_use]
    pub fn rgb8(&self) -> Vec<u8> {
        self.color.iter().flat_map(|c| c.map(to_srgb8)).collect()
    }
}

impl Frame {
    /// Writes the centre samples' AOVs as a 32-bit float OpenEXR file: `Z` (hit distance, NaN
    /// where the ray missed), `N.X`, `N.Y`, `N.Z` (unit normal facing the camera, zero on a
    /// miss) and `id` (base triangle, as an unsigned integer channel; 2^32 - 1 on a miss).
    ///
    /// # Errors
    /// When the file cannot be written.
    pub fn write_aovs_exr(&self, path: &std::path::Path) -> Result<(), String> {
        use exr::prelude::*;
        let w = self.width;
        let channels = SpecificChannels::build()
            .with_channel("Z")
            .with_channel("N.X")
            .with_channel("N.Y")
            .with_channel("N.Z")
            .with_channel("id")
            .with_pixel_fn(|p: Vec2<usize>| {
                let i = p.y() * w + p.x();
                let n = self.normal[i];
                (self.depth[i] as f32, n[0], n[1], n[2], self.hit_id[i])
            });
        Image::from_channels((self.width, self.height), channels)
            .write()
            .to_file(path)
            .map_err(|e| format!("cannot write {}: {e}", path.display()))
    }
}

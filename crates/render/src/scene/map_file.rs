//! Height-map files of a scene file: grayscale PNG (8 or 16 bits), OpenEXR and grayscale
//! TIFF, read into a [`HeightField`] with their size checked from the header first.

use nlrt_accel::{HeightField, Wrap};
use std::path::Path;

/// How large the next height map of a scene file may be: its largest side, and the samples
/// left to the file (all of its objects' maps together hold at most as many samples as one
/// map of the largest side, so a file of many objects cannot multiply the memory).
#[derive(Clone, Copy)]
pub(crate) struct MapLimit {
    pub(crate) side: usize,
    pub(crate) samples: usize,
}

/// Whether a `w x h` map fits `limit`, with the message that says why not.
fn check_map_size(w: usize, h: usize, limit: MapLimit) -> Result<(), String> {
    let max_side = limit.side;
    if w > max_side || h > max_side {
        return Err(format!(
            "height map is {w} x {h}; the largest side a scene file may use is {max_side}"
        ));
    }
    if w.saturating_mul(h) > limit.samples {
        return Err(format!(
            "height map is {w} x {h}; the scene file's maps together may hold {} samples (one map of side {max_side}), and {} are left",
            max_side * max_side,
            limit.samples
        ));
    }
    Ok(())
}

/// A grayscale PNG (8 or 16 bits), an OpenEXR file or a grayscale TIFF (by the extension) as
/// a height field. Values of EXR and TIFF files must lie in `[0, 1]`, or `normalize` maps the
/// file's range onto it.
pub(crate) fn load_height_map(
    path: &Path,
    bytes: &[u8],
    limit: MapLimit,
    normalize: bool,
) -> Result<HeightField, String> {
    let err = |m: String| format!("{}: {m}", path.display());
    let extension = path.extension().map(|e| e.to_ascii_lowercase());
    match extension.as_ref().and_then(|e| e.to_str()) {
        Some("exr") => return load_exr_height_map(path, bytes, limit, normalize),
        Some("tif" | "tiff") => {
            return load_tiff_height_map(path, bytes, limit, normalize);
        }
        _ => {}
    }
    let mut decoder = png::Decoder::new(std::io::Cursor::new(bytes));
    decoder.set_transformations(png::Transformations::IDENTITY);
    let mut reader = decoder
        .read_info()
        .map_err(|e| err(format!("not a readable PNG: {e}")))?;
    let header = reader.info();
    check_map_size(header.width as usize, header.height as usize, limit).map_err(err)?;
    let mut buf = vec![
        0;
        reader
            .output_buffer_size()
            .ok_or_else(|| err("image too large".into()))?
    ];
    let info = reader
        .next_frame(&mut buf)
        .map_err(|e| err(format!("not a readable PNG: {e}")))?;
    let (w, h) = (info.width as usize, info.height as usize);
    let channels = match info.color_type {
        png::ColorType::Grayscale => 1,
        png::ColorType::GrayscaleAlpha => 2,
        other => {
            return Err(err(format!(
                "height maps must be grayscale PNGs (8 or 16 bits); this one is {other:?}"
            )));
        }
    };
    let samples: Vec<u16> = match info.bit_depth {
        png::BitDepth::Eight => buf[..w * h * channels]
            .chunks_exact(channels)
            .map(|c| u16::from(c[0]) * 257)
            .collect(),
        png::BitDepth::Sixteen => buf[..w * h * channels * 2]
            .chunks_exact(2 * channels)
            .map(|c| u16::from_be_bytes([c[0], c[1]]))
            .collect(),
        other => {
            return Err(err(format!(
                "height maps must have 8 or 16 bits per sample; this one has {other:?}"
            )));
        }
    };
    HeightField::new(w, h, samples, Wrap::Repeat).map_err(|e| err(e.to_string()))
}

/// An OpenEXR height map: one channel (`Y`, else `R`, else the only one) of heights in
/// `[0, 1]`, quantised to the 16-bit samples the height field stores (the nearest of 65,536
/// levels: a relative step of 1.5e-5 of the height scale).
fn load_exr_height_map(
    path: &Path,
    bytes: &[u8],
    limit: MapLimit,
    normalize: bool,
) -> Result<HeightField, String> {
    use exr::prelude::*;
    let err = |m: String| format!("{}: {m}", path.display());
    // The header first: a small file may claim any size, and reading it would allocate that.
    let meta = exr::meta::MetaData::read_from_buffered(std::io::Cursor::new(bytes), false)
        .map_err(|e| err(format!("not a readable OpenEXR file: {e}")))?;
    for header in &meta.headers {
        let size = header.layer_size;
        check_map_size(size.width(), size.height(), limit).map_err(err)?;
    }
    let image = read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .first_valid_layer()
        .all_attributes()
        .from_buffered(std::io::Cursor::new(bytes))
        .map_err(|e| err(format!("not a readable OpenEXR file: {e}")))?;
    let layer = &image.layer_data;
    let (w, h) = (layer.size.width(), layer.size.height());
    let list = &layer.channel_data.list;
    let named = |n: &str| list.iter().find(|c| c.name.eq(n));
    let channel = named("Y")
        .or_else(|| named("R"))
        .or_else(|| (list.len() == 1).then(|| &list[0]))
        .ok_or_else(|| {
            let names: Vec<String> = list.iter().map(|c| c.name.to_string()).collect();
            err(format!(
                "no height channel: expected Y, R or a single channel, found {}",
                names.join(", ")
            ))
        })?;
    let values: Vec<f64> = channel.sample_data.values_as_f32().map(f64::from).collect();
    let samples = unit_samples(&values, w, normalize).map_err(err)?;
    HeightField::new(w, h, samples, Wrap::Repeat).map_err(|e| err(e.to_string()))
}

/// A grayscale TIFF height map (one sample per pixel: 8-, 16-, 32- or 64-bit integers or
/// 16-, 32- or 64-bit floats, the usual DEM export), through the `tiff` crate. Integer
/// images are read as fractions of their type's range (as PNG samples are); float images
/// are heights, in `[0, 1]` or normalised from the file's range by `normalize`.
fn load_tiff_height_map(
    path: &Path,
    bytes: &[u8],
    limit: MapLimit,
    normalize: bool,
) -> Result<HeightField, String> {
    use tiff::decoder::{Decoder, DecodingResult, Limits};
    let err = |m: String| format!("{}: {m}", path.display());
    let unreadable = |e: tiff::TiffError| err(format!("not a readable TIFF file: {e}"));
    let mut decoder = Decoder::new(std::io::Cursor::new(bytes)).map_err(unreadable)?;
    // The header first: a small file may claim any size, and decoding would allocate it.
    let (w, h) = decoder.dimensions().map_err(unreadable)?;
    let (w, h) = (w as usize, h as usize);
    check_map_size(w, h, limit).map_err(err)?;
    match decoder.colortype().map_err(unreadable)? {
        tiff::ColorType::Gray(_) => {}
        other => {
            return Err(err(format!(
                "height maps must be grayscale (one sample per pixel); this TIFF is {other:?}"
            )));
        }
    }
    // Room for the largest map in the widest sample type (64 bits), no more.
    let mut limits = Limits::default();
    limits.decoding_buffer_size = limit.side * limit.side * 8;
    limits.intermediate_buffer_size = limits.decoding_buffer_size;
    let mut decoder = decoder.with_limits(limits);
    let fraction = |v: f64, max: f64| v / max;
    let values: Vec<f64> = match decoder.read_image().map_err(unreadable)? {
        DecodingResult::U8(v) => v.iter().map(|&x| fraction(f64::from(x), 255.0)).collect(),
        DecodingResult::U16(v) => v.iter().map(|&x| fraction(f64::from(x), 65535.0)).collect(),
        DecodingResult::U32(v) => v
            .iter()
            .map(|&x| fraction(f64::from(x), f64::from(u32::MAX)))
            .collect(),
        DecodingResult::U64(v) => v
            .iter()
            .map(|&x| fraction(x as f64, u64::MAX as f64))
            .collect(),
        DecodingResult::F16(v) => v.iter().map(|&x| f64::from(x)).collect(),
        DecodingResult::F32(v) => v.iter().map(|&x| f64::from(x)).collect(),
        DecodingResult::F64(v) => v,
        DecodingResult::I8(_)
        | DecodingResult::I16(_)
        | DecodingResult::I32(_)
        | DecodingResult::I64(_) => {
            return Err(err(
                "signed integer TIFFs are not read: export heights as unsigned integers or floats"
                    .into(),
            ));
        }
    };
    if values.len() != w * h {
        return Err(err(format!(
            "the TIFF holds {} samples for {w} x {h} pixels (one grayscale sample per pixel)",
            values.len()
        )));
    }
    let samples = unit_samples(&values, w, normalize).map_err(err)?;
    HeightField::new(w, h, samples, Wrap::Repeat).map_err(|e| err(e.to_string()))
}

/// Heights (row-major, `width` per row) as 16-bit samples: each in `[0, 1]`, or with
/// `normalize` the file's range mapped onto `[0, 1]` (a DEM in metres). A value that is not
/// finite (a DEM's no-data) or, without `normalize`, outside `[0, 1]` is one message naming
/// the pixel and the file's range.
fn unit_samples(values: &[f64], width: usize, normalize: bool) -> Result<Vec<u16>, String> {
    let pixel = |i: usize| format!("({}, {})", i % width, i / width);
    if let Some(i) = values.iter().position(|v| !v.is_finite()) {
        return Err(format!(
            "height {} at pixel {} is not a finite number (fill a DEM's no-data pixels first)",
            values[i],
            pixel(i)
        ));
    }
    let (lo, hi) = values
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &v| {
            (lo.min(v), hi.max(v))
        });
    let (offset, span) = if normalize {
        (lo, if hi > lo { hi - lo } else { 1.0 })
    } else {
        if let Some(i) = values.iter().position(|v| !(0.0..=1.0).contains(v)) {
            return Err(format!(
                "height {} at pixel {} is outside [0, 1]; the file's heights span [{lo}, {hi}]: scale them into [0, 1], or set normalize = true in [displacement] to map that range onto it (height_scale is then the world height of {})",
                values[i],
                pixel(i),
                hi - lo
            ));
        }
        (0.0, 1.0)
    };
    let unit = f64::from(u16::MAX);
    Ok(values
        .iter()
        .map(|v| (((v - offset) / span).clamp(0.0, 1.0) * unit).round() as u16)
        .collect())
}

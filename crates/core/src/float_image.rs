//! Linear float output: an [`Image`]'s radiance as it was rendered, before any tone
//! curve, sRGB encoding or clip, as OpenEXR (`.exr`, through the `exr` crate) or as a
//! Portable Float Map (`.pfm`). Both are written atomically: a failure leaves no file.

use std::io::Cursor;
use std::path::Path;

use crate::error::RenderError;
use crate::image::Image;

/// A linear float image format, chosen by the output's extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FloatFormat {
    /// OpenEXR: RGBA, 32-bit float, ZIP-free lossless RLE compression, Rec. 709
    /// primaries and D65 white in its `chromaticities` attribute.
    Exr,
    /// Portable Float Map: RGB, 32-bit float, little-endian, rows bottom to top.
    Pfm,
}

impl FloatFormat {
    /// The format of `path`'s extension (`.exr` or `.pfm`, any case), `None` for any
    /// other.
    pub fn of_path(path: &Path) -> Option<FloatFormat> {
        let ext = path.extension()?.to_str()?.to_ascii_lowercase();
        match ext.as_str() {
            "exr" => Some(FloatFormat::Exr),
            "pfm" => Some(FloatFormat::Pfm),
            _ => None,
        }
    }
}

impl Image {
    /// The image as a Portable Float Map's bytes (`PF`, three channels, scale -1:
    /// little-endian; rows from the bottom up, as the format stores them). Written by
    /// hand: the format is a three-line text header and the raw floats, and no
    /// maintained crate writes it alone.
    pub fn encode_pfm(&self) -> Vec<u8> {
        let header = format!("PF\n{} {}\n-1.0\n", self.width, self.height);
        let mut out = Vec::with_capacity(header.len() + self.rgb.len() * 12);
        out.extend_from_slice(header.as_bytes());
        let w = self.width as usize;
        for row in self.rgb.chunks_exact(w.max(1)).rev() {
            for c in row.iter().flatten() {
                out.extend_from_slice(&c.to_le_bytes());
            }
        }
        out
    }

    /// The image as an OpenEXR file's bytes: R, G, B and A (the accumulated
    /// opacity) as 32-bit floats, the colours as rendered (over the background: with
    /// the default black background, premultiplied by A as OpenEXR expects), Rec. 709
    /// (sRGB) primaries and D65 white stated in the `chromaticities` attribute.
    pub fn encode_exr(&self) -> Result<Vec<u8>, RenderError> {
        use exr::meta::attribute::Chromaticities;
        use exr::prelude::{
            Encoding, Layer, LayerAttributes, SpecificChannels, Vec2, WritableImage,
        };
        let w = self.width as usize;
        let pixels = SpecificChannels::rgba(|p: Vec2<usize>| {
            let i = p.y() * w + p.x();
            let [r, g, b] = self.rgb[i];
            (r, g, b, self.alpha[i])
        });
        let layer = Layer::new(
            (w, self.height as usize),
            LayerAttributes::named("glint"),
            Encoding::FAST_LOSSLESS,
            pixels,
        );
        let mut image = exr::prelude::Image::from_layer(layer);
        image.attributes.chromaticities = Some(Chromaticities {
            red: Vec2(0.64, 0.33),
            green: Vec2(0.30, 0.60),
            blue: Vec2(0.15, 0.06),
            white: Vec2(0.3127, 0.3290),
        });
        let mut out = Cursor::new(Vec::new());
        image
            .write()
            .non_parallel()
            .to_buffered(&mut out)
            .map_err(|e| RenderError::EncodeExr(e.to_string()))?;
        Ok(out.into_inner())
    }

    /// The image in `format`'s bytes.
    pub fn encode_float(&self, format: FloatFormat) -> Result<Vec<u8>, RenderError> {
        match format {
            FloatFormat::Exr => self.encode_exr(),
            FloatFormat::Pfm => Ok(self.encode_pfm()),
        }
    }

    /// Writes the image's linear radiance to `path` as `format`, atomically
    /// ([`glint_io::write_atomic`]): a failure leaves no partial file.
    pub fn write_float(&self, path: &Path, format: FloatFormat) -> Result<(), RenderError> {
        let bytes = self.encode_float(format)?;
        glint_io::write_atomic(path, |out| out.write_all(&bytes)).map_err(RenderError::Write)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn image() -> Image {
        Image {
            width: 3,
            height: 2,
            rgb: vec![
                [0.0, 1.5, 1e-8],
                [7.25, 0.5, 0.125],
                [1e6, 0.0, 2.0],
                [0.3, 0.2, 0.1],
                [f32::MIN_POSITIVE, 1.0, 65504.0],
                [0.75, 0.75, 0.75],
            ],
            alpha: vec![0.0, 0.25, 1.0, 0.5, 1.0, 0.125],
            stats: Default::default(),
        }
    }

    #[test]
    fn formats_by_extension() {
        assert_eq!(
            FloatFormat::of_path(Path::new("a.EXR")),
            Some(FloatFormat::Exr)
        );
        assert_eq!(
            FloatFormat::of_path(Path::new("d/a.pfm")),
            Some(FloatFormat::Pfm)
        );
        assert_eq!(FloatFormat::of_path(Path::new("a.png")), None);
        assert_eq!(FloatFormat::of_path(Path::new("exr")), None);
    }

    #[test]
    fn pfm_round_trip_is_exact() {
        let img = image();
        let bytes = img.encode_pfm();
        let header = b"PF\n3 2\n-1.0\n";
        assert_eq!(&bytes[..header.len()], header);
        let floats: Vec<f32> = bytes[header.len()..]
            .chunks_exact(4)
            .map(|b| f32::from_le_bytes(b.try_into().unwrap()))
            .collect();
        assert_eq!(floats.len(), 18);
        // Bottom row first.
        for (y, file_row) in [1usize, 0].iter().enumerate() {
            for x in 0..3 {
                let px = img.rgb[file_row * 3 + x];
                assert_eq!(
                    &floats[(y * 3 + x) * 3..][..3],
                    &px[..],
                    "({x}, {file_row})"
                );
            }
        }
    }

    #[test]
    fn exr_round_trip_is_exact() {
        let img = image();
        let dir = std::env::temp_dir().join(format!("glint-exr-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("x.exr");
        img.write_float(&path, FloatFormat::Exr).unwrap();
        let read = exr::prelude::read_first_rgba_layer_from_file(
            &path,
            |res, _| (res.width(), vec![[0f32; 4]; res.width() * res.height()]),
            |(w, px), p, (r, g, b, a): (f32, f32, f32, f32)| px[p.y() * *w + p.x()] = [r, g, b, a],
        )
        .unwrap();
        std::fs::remove_dir_all(&dir).unwrap();
        let (w, px) = &read.layer_data.channel_data.pixels;
        assert_eq!((*w, read.layer_data.size.height()), (3, 2));
        for (i, p) in px.iter().enumerate() {
            let [r, g, b] = img.rgb[i];
            // Compared as bits: the floats come back exactly.
            assert_eq!(
                p.map(f32::to_bits),
                [r, g, b, img.alpha[i]].map(f32::to_bits)
            );
        }
        let c = read
            .attributes
            .chromaticities
            .expect("chromaticities written");
        assert_eq!((c.white.0, c.white.1), (0.3127, 0.3290));
        // A directory that does not exist: an error, and no file.
        let bad = dir.join("missing").join("x.exr");
        assert!(img.write_float(&bad, FloatFormat::Exr).is_err());
        assert!(!bad.exists());
    }
}

//! Animated WebP: every frame encoded losslessly (VP8L) by `image-webp` (image-rs's
//! pure-Rust WebP codec), the frames put into the animation container here.
//!
//! Why the container is written by hand: `image-webp` 0.2 encodes still images only
//! (its encoder has no animation), and the crates that write animated WebP
//! (`webp-animation`, `webp`) wrap libwebp's C sources through `libwebp-sys`, a C
//! library compiled into every build of `glint` for one output format. The container
//! is small and fixed (Google's "WebP Container Specification", extended format): a
//! `RIFF` header, a `VP8X` chunk (canvas size, the animation flag), an `ANIM` chunk
//! (background, loop count) and one `ANMF` chunk per frame holding its position,
//! size, duration and the frame's `VP8L` chunk as `image-webp` wrote it.

use std::fs::File;
use std::io::{BufWriter, Seek, SeekFrom, Write};

/// The largest side of a VP8L frame (14 bits of width and height).
pub(crate) const MAX_WEBP_SIDE: u32 = 16_384;

/// An animated WebP being written to a file.
pub(crate) struct WebPSink {
    out: BufWriter<File>,
    /// Bytes written after the RIFF size field (the size field's value).
    riff_bytes: u64,
    width: u32,
    height: u32,
    /// Each frame's duration, ms.
    duration_ms: u32,
}

/// Why a frame or the file could not be written.
#[derive(Debug, thiserror::Error)]
pub(crate) enum WebPError {
    #[error(transparent)]
    Encode(#[from] image_webp::EncodingError),
    #[error(transparent)]
    Io(#[from] std::io::Error),
    #[error("the animation is larger than a WebP file can hold (4 GiB)")]
    TooLarge,
}

/// Writes chunk `name` holding `data` (padded to an even size).
fn chunk(out: &mut impl Write, name: &[u8; 4], data: &[u8]) -> std::io::Result<u64> {
    out.write_all(name)?;
    out.write_all(&(data.len() as u32).to_le_bytes())?;
    out.write_all(data)?;
    let pad = data.len() % 2;
    if pad == 1 {
        out.write_all(&[0])?;
    }
    Ok(8 + data.len() as u64 + pad as u64)
}

/// The low three bytes of `v` (the container's 24-bit fields), little-endian.
fn u24(v: u32) -> [u8; 3] {
    let b = v.to_le_bytes();
    [b[0], b[1], b[2]]
}

impl WebPSink {
    /// Starts an animation of `width` x `height` frames (each at most
    /// [`MAX_WEBP_SIDE`]: the caller checks) at `fps`, looping forever, in `file`.
    pub(crate) fn start(file: File, width: u32, height: u32, fps: u32) -> Result<Self, WebPError> {
        let mut out = BufWriter::new(file);
        out.write_all(b"RIFF")?;
        out.write_all(&0u32.to_le_bytes())?; // the size, written by `finish`
        out.write_all(b"WEBP")?;
        let mut riff_bytes = 4;
        // VP8X: flags (bit 1: animation; no alpha, ICC, EXIF or XMP), 3 reserved bytes,
        // the canvas's width - 1 and height - 1 in 24 bits each.
        let mut vp8x = vec![0b0000_0010, 0, 0, 0];
        vp8x.extend(u24(width - 1));
        vp8x.extend(u24(height - 1));
        riff_bytes += chunk(&mut out, b"VP8X", &vp8x)?;
        // ANIM: background colour (BGRA, opaque black), loop count 0 (forever).
        riff_bytes += chunk(&mut out, b"ANIM", &[0, 0, 0, 255, 0, 0])?;
        Ok(WebPSink {
            out,
            riff_bytes,
            width,
            height,
            duration_ms: (1000.0 / f64::from(fps.max(1))).round().max(1.0) as u32,
        })
    }

    /// Adds a frame of 8-bit sRGB `rgb` (the canvas's size), encoded losslessly.
    pub(crate) fn frame(&mut self, rgb: &[u8]) -> Result<(), WebPError> {
        let mut still = Vec::new();
        image_webp::WebPEncoder::new(&mut still).encode(
            rgb,
            self.width,
            self.height,
            image_webp::ColorType::Rgb8,
        )?;
        // A still without metadata is the simple format: "RIFF" size "WEBP" and one
        // "VP8L" chunk, which the frame carries as it is.
        let vp8l = &still[12..];
        debug_assert_eq!(&vp8l[..4], b"VP8L");
        // ANMF: x / 2 and y / 2 (24 bits each, 0: the frame covers the canvas), width
        // - 1, height - 1, duration (ms), flags (bit 1: do not blend; dispose none).
        let mut anmf = Vec::with_capacity(16 + vp8l.len());
        anmf.extend(u24(0));
        anmf.extend(u24(0));
        anmf.extend(u24(self.width - 1));
        anmf.extend(u24(self.height - 1));
        anmf.extend(u24(self.duration_ms));
        anmf.push(0b0000_0010);
        anmf.extend_from_slice(vp8l);
        if self.riff_bytes + 8 + anmf.len() as u64 + 1 > u64::from(u32::MAX) {
            return Err(WebPError::TooLarge);
        }
        self.riff_bytes += chunk(&mut self.out, b"ANMF", &anmf)?;
        Ok(())
    }

    /// Writes the RIFF size and flushes the file.
    pub(crate) fn finish(self) -> Result<(), WebPError> {
        let mut file = self.out.into_inner().map_err(|e| e.into_error())?;
        file.seek(SeekFrom::Start(4))?;
        file.write_all(&(self.riff_bytes as u32).to_le_bytes())?;
        file.flush()?;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Frames written here decode with `image-webp`'s decoder (separate code from its
    /// encoder) to the same pixels, in order, with the frame rate's duration.
    #[test]
    fn frames_decode_back_bit_for_bit() {
        let (w, h) = (7u32, 5u32);
        let frames: Vec<Vec<u8>> = (0..3u8)
            .map(|k| {
                (0..w * h * 3)
                    .map(|i| (i as u8).wrapping_mul(37).wrapping_add(k * 80))
                    .collect()
            })
            .collect();
        let tmp = tempfile::tempfile().unwrap();
        let mut sink = WebPSink::start(tmp.try_clone().unwrap(), w, h, 25).unwrap();
        for f in &frames {
            sink.frame(f).unwrap();
        }
        sink.finish().unwrap();
        let mut tmp = tmp;
        tmp.seek(SeekFrom::Start(0)).unwrap();
        let mut decoder =
            image_webp::WebPDecoder::new(std::io::BufReader::new(tmp)).expect("a WebP file");
        assert!(decoder.is_animated());
        assert_eq!(decoder.dimensions(), (w, h));
        assert_eq!(decoder.num_frames(), 3);
        assert!(matches!(
            decoder.loop_count(),
            image_webp::LoopCount::Forever
        ));
        let mut buf = vec![0u8; decoder.output_buffer_size().unwrap()];
        for f in &frames {
            let ms = decoder.read_frame(&mut buf).unwrap();
            assert_eq!(ms, 40);
            // Decoded as RGB or RGBA (an animation's canvas): the RGB of every pixel
            // equal.
            let channels = buf.len() / (w * h) as usize;
            let rgb: Vec<u8> = buf.chunks(channels).flat_map(|p| p[..3].to_vec()).collect();
            assert_eq!(&rgb, f);
        }
    }
}

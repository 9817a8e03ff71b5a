//! Checks on compressed pixel data before it reaches a decoder: the decoders of
//! dicom-transfer-syntax-registry 0.10 size their buffers by the codestream and copy into
//! one sized by Rows and Columns, and index RLE segments without bounds checks, so a
//! lying codestream would panic or allocate there.

use std::path::Path;

use super::invalid;
use super::scan::ts_name;
use crate::IoError;

/// Checks that an RLE Lossless frame (PS3.5 Annex G) has a segment for every byte of a
/// sample and that each decodes to at least `pixels` bytes: dicom-rs 0.10 indexes the
/// decoded segment up to Rows x Columns and unwraps read errors, so a short or cut
/// segment panics there (found by fuzzing). The PackBits walk (G.3.1) only counts.
pub(super) fn check_rle(
    path: &Path,
    frame: &[u8],
    bytes: usize,
    pixels: usize,
) -> Result<(), IoError> {
    let bad = |what: String| invalid(path, format!("RLE Lossless: {what}"));
    let le32 = |i: usize| u32::from_le_bytes([frame[i], frame[i + 1], frame[i + 2], frame[i + 3]]);
    if frame.len() < 64 {
        return Err(bad(format!(
            "a {}-byte frame has no 64-byte header",
            frame.len()
        )));
    }
    let n = le32(0) as usize;
    if !(bytes..=15).contains(&n) {
        return Err(bad(format!("{n} segments for {bytes}-byte samples")));
    }
    for seg in 0..bytes {
        let start = le32(4 + 4 * seg) as usize;
        let end = if seg + 1 < n {
            le32(8 + 4 * seg) as usize
        } else {
            frame.len()
        };
        let Some(data) = frame.get(start..end) else {
            return Err(bad(format!(
                "segment {seg} spans bytes {start}..{end} of {}",
                frame.len()
            )));
        };
        let (mut i, mut out) = (0usize, 0usize);
        while out < pixels {
            let Some(&c) = data.get(i) else {
                return Err(bad(format!(
                    "segment {seg} decodes to {out} bytes, Rows x Columns is {pixels}"
                )));
            };
            let c = c as i8;
            let (take, produce) = match c {
                0..=127 => (1 + c as usize, 1 + c as usize),
                -128 => (0, 0),
                _ => (1, 1 + c.unsigned_abs() as usize),
            };
            if i + 1 + take > data.len() {
                return Err(bad(format!("segment {seg} ends inside a run")));
            }
            i += 1 + take;
            out += produce;
        }
    }
    Ok(())
}

/// Sizes a codestream may declare: at most `limit` (Rows x Columns x SamplesPerPixel)
/// samples.
struct Bound<'a> {
    path: &'a Path,
    limit: usize,
}

impl Bound<'_> {
    fn too_big(&self, kind: &str, w: u64, h: u64, c: u64) -> IoError {
        invalid(
            self.path,
            format!(
                "the {kind} codestream declares {w} x {h} x {c} samples, more than Rows x \
                 Columns x SamplesPerPixel = {}",
                self.limit
            ),
        )
    }
}

fn be16(b: &[u8]) -> u64 {
    u64::from(u16::from_be_bytes([b[0], b[1]]))
}

fn be32(b: &[u8]) -> u64 {
    u64::from(u32::from_be_bytes([b[0], b[1], b[2], b[3]]))
}

/// Checks the image size a JPEG (SOF marker), JPEG-LS (SOF55) or JPEG 2000 (SIZ marker)
/// codestream declares against the `limit` of Rows x Columns x SamplesPerPixel samples.
pub(super) fn check_codestream(
    path: &Path,
    ts: &str,
    data: &[u8],
    limit: usize,
    samples_per_pixel: u16,
) -> Result<(), IoError> {
    let b = Bound { path, limit };
    if ts.starts_with("1.2.840.10008.1.2.4.5") || ts.starts_with("1.2.840.10008.1.2.4.7") {
        check_jpeg(&b, ts, data)
    } else if super::jpegls::is_jpeg_ls(ts) {
        check_jpeg_ls(&b, data)
    } else if ts.starts_with("1.2.840.10008.1.2.4.9") || ts.starts_with("1.2.840.10008.1.2.4.20") {
        check_j2k(&b, data, samples_per_pixel)
    } else {
        Ok(())
    }
}

/// JPEG frame headers, and their precision.
fn check_jpeg(b: &Bound, ts: &str, data: &[u8]) -> Result<(), IoError> {
    let path = b.path;
    // JPEG: start-of-frame markers FFC0-FFCF except DHT (C4), JPG (C8), DAC (CC);
    // entropy-coded data never holds FF followed by these (PS3.5 A.4.1, ITU T.81
    // B.1.1.2), so a byte scan finds every frame header.
    for (i, w) in data.windows(2).enumerate() {
        if w[0] == 0xFF && (0xC0..=0xCF).contains(&w[1]) && ![0xC4, 0xC8, 0xCC].contains(&w[1]) {
            let Some(sof) = data.get(i + 4..i + 10) else {
                continue;
            };
            let (height, width, comps) = (be16(&sof[1..]), be16(&sof[3..]), u64::from(sof[5]));
            if height * width * comps > b.limit as u64 {
                return Err(b.too_big("JPEG", width, height, comps));
            }
            // 8-bit DCT and 2-16-bit lossless (SOF3) go to jpeg-decoder, 12-bit DCT
            // to libjpeg-turbo (see `jpeg`); other precisions do not exist in DICOM
            // (PS3.5 A.4.1: 8 or 12 bits for processes 1, 2 and 4).
            if sof[0] != 8 && sof[0] != 12 && w[1] != 0xC3 {
                return Err(IoError::Unsupported {
                    path: path.into(),
                    what: format!(
                        "{}-bit lossy JPEG (transfer syntax {}): lossy JPEG has 8 or \
                         12 bits",
                        sof[0],
                        ts_name(ts)
                    ),
                });
            }
        }
    }
    Ok(())
}

fn check_jpeg_ls(b: &Bound, data: &[u8]) -> Result<(), IoError> {
    let path = b.path;
    // JPEG-LS: SOF55 (FFF7) has the layout of a JPEG frame header (ITU T.87 C.2.2):
    // Lf, P, Y, X, Nf. CharLS decodes into a buffer of the size it declares. In the
    // coded data an FF is followed by a byte below 0x80 (T.87 A.1), so a byte scan finds
    // every frame's header (`data` is all fragments together).
    let mut found = false;
    for (at, _) in data
        .windows(2)
        .enumerate()
        .filter(|(_, w)| *w == [0xFF, 0xF7])
    {
        found = true;
        let Some(sof) = data.get(at + 4..at + 10) else {
            return Err(invalid(path, "a JPEG-LS frame header cut short"));
        };
        let (height, width, comps) = (be16(&sof[1..]), be16(&sof[3..]), u64::from(sof[5]));
        if height * width * comps > b.limit as u64 {
            return Err(b.too_big("JPEG-LS", width, height, comps));
        }
    }
    if !found {
        return Err(invalid(
            path,
            "JPEG-LS pixel data without a frame header (SOF55)",
        ));
    }
    Ok(())
}

fn check_j2k(b: &Bound, data: &[u8], samples_per_pixel: u16) -> Result<(), IoError> {
    let path = b.path;
    // JPEG 2000: SOC (FF4F) then SIZ (FF51): Lsiz, Rsiz, Xsiz, Ysiz, XOsiz, YOsiz,
    // XTsiz, YTsiz, XTOsiz, YTOsiz, Csiz (ISO 15444-1 A.5.1). `data` is every
    // fragment of the pixel data: a frame's codestream may start in any fragment
    // (after empty ones) and run over several, so each codestream header found is
    // checked, and there must be one.
    let mut found = false;
    let mut from = 0;
    while let Some(at) = data[from..]
        .windows(4)
        .position(|w| w == [0xFF, 0x4F, 0xFF, 0x51])
        .map(|i| from + i)
    {
        found = true;
        from = at + 4;
        let Some(siz) = data.get(at + 4..at + 4 + 38) else {
            return Err(invalid(path, "a JPEG 2000 codestream header cut short"));
        };
        let (x, y, x0, y0) = (
            be32(&siz[4..]),
            be32(&siz[8..]),
            be32(&siz[12..]),
            be32(&siz[16..]),
        );
        let comps = be16(&siz[36..]);
        let (w, h) = (x.saturating_sub(x0), y.saturating_sub(y0));
        if comps != samples_per_pixel as u64 {
            return Err(invalid(
                path,
                format!(
                    "the JPEG 2000 codestream has {comps} components, SamplesPerPixel \
                     is {samples_per_pixel}"
                ),
            ));
        }
        if w * h * comps > b.limit as u64 {
            return Err(b.too_big("JPEG 2000", w, h, comps));
        }
    }
    if !found {
        return Err(invalid(
            path,
            "JPEG 2000 pixel data without a codestream header (SOC, SIZ)",
        ));
    }
    Ok(())
}

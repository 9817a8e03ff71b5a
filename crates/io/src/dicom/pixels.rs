//! Pixel data: native (uncompressed, any byte order and VR) read directly; encapsulated
//! (JPEG baseline, extended and lossless, JPEG 2000, RLE) decoded by dicom-pixeldata
//! after the codestream headers are checked against Rows and Columns.

use std::path::Path;

use dicom_core::value::{PrimitiveValue, Value};
use dicom_dictionary_std::tags;
use dicom_object::{FileDicomObject, InMemDicomObject};
use dicom_pixeldata::PixelDecoder;

use super::header::Header;
use super::scan::{self, ts_name};
use super::{invalid, one_line};
use crate::{IoError, Samples};

const EXPLICIT_BE: &str = "1.2.840.10008.1.2.2";
const RLE_LOSSLESS: &str = "1.2.840.10008.1.2.5";

/// Reads a file's pixel data and splits it into frames of `frame_len` samples.
pub(super) fn read_pixels(
    h: &Header,
    frame_len: usize,
    strict: bool,
) -> Result<Vec<Samples>, IoError> {
    let path = h.path.as_path();
    let obj = scan::load(path, true, strict)?.obj;
    let total = frame_len * h.frames;
    let words = if h.encapsulated {
        decode(h, &obj, total)?
    } else {
        native_words(h, &obj, total)?
    };
    if words.len() < total {
        return Err(IoError::SizeMismatch {
            path: path.into(),
            what: format!(
                "{} rows x {} columns x {} frames of {}-bit pixels need {total} samples, \
                 PixelData holds {}",
                h.rows,
                h.cols,
                h.frames,
                h.bits_allocated,
                words.len()
            ),
        });
    }
    Ok(split_frames(h, &words, frame_len))
}

/// The stored words of native pixel data as u32, whatever VR the file used.
fn native_words(
    h: &Header,
    obj: &FileDicomObject<InMemDicomObject>,
    total: usize,
) -> Result<Vec<u32>, IoError> {
    let path = h.path.as_path();
    let big_endian = h.ts == EXPLICIT_BE;
    let elem = obj
        .element(tags::PIXEL_DATA)
        .map_err(|_| invalid(path, "no PixelData"))?;
    let bits = h.bits_allocated;
    Ok(match elem.value() {
        Value::PixelSequence(_) => {
            return Err(invalid(
                path,
                format!(
                    "encapsulated pixel data in the native transfer syntax {}",
                    ts_name(&h.ts)
                ),
            ))
        }
        Value::Primitive(PrimitiveValue::U8(bytes)) => {
            bytes_to_words(bytes, usize::from(bits / 8), big_endian, total)
        }
        Value::Primitive(PrimitiveValue::U16(w)) => match bits {
            16 => w.iter().take(total).map(|&x| u32::from(x)).collect(),
            // 8-bit pixels packed two to a little-endian word.
            8 => w
                .iter()
                .flat_map(|x| x.to_le_bytes())
                .take(total)
                .map(u32::from)
                .collect(),
            _ => w
                .chunks_exact(2)
                .take(total)
                .map(|c| {
                    let (lo, hi) = if big_endian {
                        (c[1], c[0])
                    } else {
                        (c[0], c[1])
                    };
                    u32::from(lo) | (u32::from(hi) << 16)
                })
                .collect(),
        },
        Value::Primitive(PrimitiveValue::U32(w)) => w.iter().take(total).copied().collect(),
        _ => return Err(invalid(path, "PixelData has an unexpected value type")),
    })
}

fn bytes_to_words(bytes: &[u8], per: usize, big_endian: bool, total: usize) -> Vec<u32> {
    bytes
        .chunks_exact(per)
        .take(total)
        .map(|c| match (per, big_endian) {
            (1, _) => u32::from(c[0]),
            (2, false) => u32::from(u16::from_le_bytes([c[0], c[1]])),
            (2, true) => u32::from(u16::from_be_bytes([c[0], c[1]])),
            (_, false) => u32::from_le_bytes([c[0], c[1], c[2], c[3]]),
            (_, true) => u32::from_be_bytes([c[0], c[1], c[2], c[3]]),
        })
        .collect()
}

/// Keeps the stored bits of each word, sign-extended for signed pixels (PS3.5 8.1.1),
/// and splits them into frames.
fn split_frames(h: &Header, words: &[u32], frame_len: usize) -> Vec<Samples> {
    let stored = u32::from(h.bits_stored);
    let mask = if stored >= 32 {
        u32::MAX
    } else {
        (1u32 << stored) - 1
    };
    let signed = |x: u32| -> i32 {
        let shift = 32 - stored;
        (((x & mask) << shift) as i32) >> shift
    };
    words
        .chunks_exact(frame_len)
        .take(h.frames)
        .map(|f| match (h.bits_allocated, h.signed) {
            (8, false) => Samples::U8(f.iter().map(|&x| (x & mask) as u8).collect()),
            (8, true) => Samples::I8(f.iter().map(|&x| signed(x) as i8).collect()),
            (16, false) => Samples::U16(f.iter().map(|&x| (x & mask) as u16).collect()),
            (16, true) => Samples::I16(f.iter().map(|&x| signed(x) as i16).collect()),
            (_, false) => Samples::U32(f.iter().map(|&x| x & mask).collect()),
            (_, true) => Samples::I32(f.iter().map(|&x| signed(x)).collect()),
        })
        .collect()
}

/// Decodes encapsulated pixel data with dicom-pixeldata. The decoders allocate by the
/// image size their codestream declares and copy into a buffer sized by Rows and
/// Columns (a larger codestream panics in dicom-transfer-syntax-registry 0.10), so each
/// codestream header is checked first.
fn decode(
    h: &Header,
    obj: &FileDicomObject<InMemDicomObject>,
    total: usize,
) -> Result<Vec<u32>, IoError> {
    let path = h.path.as_path();
    let elem = obj
        .element(tags::PIXEL_DATA)
        .map_err(|_| invalid(path, "no PixelData"))?;
    let Value::PixelSequence(seq) = elem.value() else {
        return Err(invalid(
            path,
            format!(
                "native pixel data in the compressed transfer syntax {}",
                ts_name(&h.ts)
            ),
        ));
    };
    let limit = h.rows * h.cols;
    for fragment in seq.fragments() {
        if h.ts == RLE_LOSSLESS {
            check_rle(path, fragment, usize::from(h.bits_allocated / 8), limit)?;
        } else {
            check_codestream(path, &h.ts, fragment, limit)?;
        }
    }
    // Backstop for decoder panics the checks above do not foresee (found by fuzzing or
    // not): a malformed file is an error, not an abort. The buffers are dropped on
    // unwind, nothing shared is left half-updated.
    let decoded = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        obj.decode_pixel_data().map(|d| d.into_data())
    }))
    .map_err(|_| {
        invalid(
            path,
            format!("the {} decoder failed on this pixel data", ts_name(&h.ts)),
        )
    })?
    .map_err(|e| {
        invalid(
            path,
            format!(
                "cannot decode {} pixel data: {}",
                ts_name(&h.ts),
                one_line(&super::chain(&e))
            ),
        )
    })?;
    Ok(bytes_to_words(
        &decoded,
        usize::from(h.bits_allocated / 8),
        false,
        total,
    ))
}

/// Checks that an RLE Lossless frame (PS3.5 Annex G) has a segment for every byte of a
/// sample and that each decodes to at least `pixels` bytes: dicom-rs 0.10 indexes the
/// decoded segment up to Rows x Columns and unwraps read errors, so a short or cut
/// segment panics there (found by fuzzing). The PackBits walk (G.3.1) only counts.
fn check_rle(path: &Path, frame: &[u8], bytes: usize, pixels: usize) -> Result<(), IoError> {
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

/// Checks the image size a JPEG (SOF marker) or JPEG 2000 (SIZ marker) codestream
/// declares against the `limit` of Rows x Columns samples.
fn check_codestream(path: &Path, ts: &str, data: &[u8], limit: usize) -> Result<(), IoError> {
    let too_big = |kind: &str, w: u64, h: u64, c: u64| {
        invalid(
            path,
            format!(
                "the {kind} codestream declares {w} x {h} x {c} samples, more than Rows x \
                 Columns = {limit}"
            ),
        )
    };
    let be16 = |b: &[u8]| u64::from(u16::from_be_bytes([b[0], b[1]]));
    let be32 = |b: &[u8]| u64::from(u32::from_be_bytes([b[0], b[1], b[2], b[3]]));
    if ts.starts_with("1.2.840.10008.1.2.4.5") || ts.starts_with("1.2.840.10008.1.2.4.7") {
        // JPEG: start-of-frame markers FFC0-FFCF except DHT (C4), JPG (C8), DAC (CC);
        // entropy-coded data never holds FF followed by these (PS3.5 A.4.1, ITU T.81
        // B.1.1.2), so a byte scan finds every frame header.
        for (i, w) in data.windows(2).enumerate() {
            if w[0] == 0xFF && (0xC0..=0xCF).contains(&w[1]) && ![0xC4, 0xC8, 0xCC].contains(&w[1])
            {
                let Some(sof) = data.get(i + 4..i + 10) else {
                    continue;
                };
                let (height, width, comps) = (be16(&sof[1..]), be16(&sof[3..]), u64::from(sof[5]));
                if height * width * comps > limit as u64 {
                    return Err(too_big("JPEG", width, height, comps));
                }
                // jpeg-decoder 0.3 decodes 8-bit DCT and 2-16-bit lossless (SOF3) frames
                // only; extended 12-bit DCT (process 4) is refused by name.
                if sof[0] != 8 && w[1] != 0xC3 {
                    return Err(IoError::Unsupported {
                        path: path.into(),
                        what: format!(
                            "{}-bit lossy JPEG (transfer syntax {}): the JPEG decoder reads \
                             8-bit lossy and lossless JPEG only",
                            sof[0],
                            ts_name(ts)
                        ),
                    });
                }
            }
        }
    } else if ts.starts_with("1.2.840.10008.1.2.4.9") || ts.starts_with("1.2.840.10008.1.2.4.20") {
        // JPEG 2000: SOC (FF4F) then SIZ (FF51): Lsiz, Rsiz, Xsiz, Ysiz, XOsiz, YOsiz,
        // XTsiz, YTsiz, XTOsiz, YTOsiz, Csiz (ISO 15444-1 A.5.1).
        let Some(at) = data.windows(4).position(|w| w == [0xFF, 0x4F, 0xFF, 0x51]) else {
            return Err(invalid(
                path,
                "a JPEG 2000 fragment without a codestream header (SOC, SIZ)",
            ));
        };
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
        if comps != 1 {
            return Err(invalid(
                path,
                format!("the JPEG 2000 codestream has {comps} components, SamplesPerPixel is 1"),
            ));
        }
        if w * h > limit as u64 {
            return Err(too_big("JPEG 2000", w, h, comps));
        }
    }
    Ok(())
}

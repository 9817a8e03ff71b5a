//! Pixel data: native (uncompressed, any byte order and VR, 1-bit packed, colour
//! interleaved or planar, YBR_FULL and YBR_FULL_422) read directly; encapsulated (JPEG
//! baseline, extended and lossless, JPEG 2000, RLE) decoded by dicom-pixeldata after the
//! codestream headers are checked against Rows and Columns, except the JPEG frames
//! `jpeg` decodes and JPEG-LS, which `jpegls` decodes.

use dicom_core::value::{PrimitiveValue, Value};
use dicom_dictionary_std::tags;
use dicom_object::{FileDicomObject, InMemDicomObject};
use dicom_pixeldata::PixelDecoder;

use super::checks::{check_codestream, check_rle};
use super::header::Header;
use super::scan::{self, ts_name};
use super::{colour, invalid, one_line};
use super::{jpeg, jpegls};
use crate::{IoError, Samples};

const EXPLICIT_BE: &str = "1.2.840.10008.1.2.2";
const RLE_LOSSLESS: &str = "1.2.840.10008.1.2.5";

/// One frame's pixels.
pub(super) enum Frame {
    /// Grey samples, Rows x Columns.
    Grey(Samples),
    /// Red, green and blue planes, Rows x Columns each.
    Rgb([Samples; 3]),
}

/// How decoded colour words are laid out.
struct Layout {
    /// The photometric interpretation of the words (after any decoder conversion).
    photometric: String,
    /// Planar configuration 1.
    planar: bool,
}

/// Reads a file's pixel data and splits it into frames of `frame_len` pixels.
pub(super) fn read_pixels(
    h: &Header,
    frame_len: usize,
    strict: bool,
) -> Result<Vec<Frame>, IoError> {
    let path = h.path.as_path();
    let obj = scan::load(path, true, strict)?.obj;
    if h.bits_allocated == 1 {
        let bits = unpack_bits(h, &obj, frame_len * h.frames)?;
        return Ok(split_frames(h, &bits, frame_len)
            .into_iter()
            .map(Frame::Grey)
            .collect());
    }
    let spp = usize::from(h.samples_per_pixel);
    let total = frame_len * h.frames * spp;
    let (words, layout) = if h.encapsulated {
        decode(h, &obj, total)?
    } else {
        native(h, &obj, frame_len)?
    };
    if words.len() < total {
        return Err(IoError::SizeMismatch {
            path: path.into(),
            what: format!(
                "{} rows x {} columns x {} frames of {spp} x {}-bit samples need {total} \
                 samples, PixelData holds {}",
                h.rows,
                h.cols,
                h.frames,
                h.bits_allocated,
                words.len()
            ),
        });
    }
    if spp == 1 {
        return Ok(split_frames(h, &words, frame_len)
            .into_iter()
            .map(Frame::Grey)
            .collect());
    }
    let ybr = layout.photometric == "YBR_FULL";
    Ok(words
        .chunks_exact(3 * frame_len)
        .take(h.frames)
        .map(|f| {
            let planes = colour::planes(f, frame_len, layout.planar, ybr);
            Frame::Rgb(planes.map(|p| colour::samples(p, h.bits_allocated)))
        })
        .collect())
}

/// Native pixel data as words; colour data is returned interleaved or planar as
/// stored, YBR_FULL_422 expanded to YBR_FULL.
fn native(
    h: &Header,
    obj: &FileDicomObject<InMemDicomObject>,
    frame_len: usize,
) -> Result<(Vec<u32>, Layout), IoError> {
    let subsampled = h.photometric == "YBR_FULL_422";
    let per_pixel = match h.samples_per_pixel {
        1 => 1,
        _ if subsampled => 2,
        _ => 3,
    };
    let words = native_words(h, obj, frame_len * h.frames * per_pixel)?;
    if subsampled {
        let layout = Layout {
            photometric: "YBR_FULL".into(),
            planar: false,
        };
        return Ok((colour::expand_422(&words), layout));
    }
    let layout = Layout {
        photometric: h.photometric.clone(),
        planar: h.planar,
    };
    Ok((words, layout))
}

/// 1-bit pixel data (BitsAllocated 1, native only): bit-packed across frames, the
/// first pixel in the least significant bit of the first byte (PS3.5 8.1.1, D.2), as
/// pydicom's `unpack_bits`. Returns one word (0 or 1) per pixel of every frame.
fn unpack_bits(
    h: &Header,
    obj: &FileDicomObject<InMemDicomObject>,
    total: usize,
) -> Result<Vec<u32>, IoError> {
    let path = h.path.as_path();
    let elem = obj
        .element(tags::PIXEL_DATA)
        .map_err(|_| invalid(path, "no PixelData"))?;
    let bytes: Vec<u8> = match elem.value() {
        Value::Primitive(PrimitiveValue::U8(b)) => b.to_vec(),
        // OW: the bytes of little-endian words in file order (dicom-rs has already
        // swapped a big-endian file's words to native order).
        Value::Primitive(PrimitiveValue::U16(w)) => {
            w.iter().flat_map(|x| x.to_le_bytes()).collect()
        }
        _ => {
            return Err(invalid(
                path,
                "1-bit PixelData has an unexpected value type",
            ))
        }
    };
    if bytes.len() * 8 < total {
        return Err(IoError::SizeMismatch {
            path: path.into(),
            what: format!(
                "{total} 1-bit pixels need {} bytes, PixelData holds {}",
                total.div_ceil(8),
                bytes.len()
            ),
        });
    }
    Ok((0..total)
        .map(|i| u32::from((bytes[i / 8] >> (i % 8)) & 1))
        .collect())
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
    let stored = u32::from(h.bits_stored.max(1));
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
            (1, _) => Samples::U8(f.iter().map(|&x| x as u8).collect()),
            (8, false) => Samples::U8(f.iter().map(|&x| (x & mask) as u8).collect()),
            (8, true) => Samples::I8(f.iter().map(|&x| signed(x) as i8).collect()),
            (16, false) => Samples::U16(f.iter().map(|&x| (x & mask) as u16).collect()),
            (16, true) => Samples::I16(f.iter().map(|&x| signed(x) as i16).collect()),
            (_, false) => Samples::U32(f.iter().map(|&x| x & mask).collect()),
            (_, true) => Samples::I32(f.iter().map(|&x| signed(x)).collect()),
        })
        .collect()
}

/// Decodes JPEG-LS frames with [`jpegls`] into what dicom-pixeldata made of CharLS's
/// output (the decoder it used before): the frames' bytes in turn, read as words of
/// BitsAllocated, RGB for three samples a pixel, planar configuration 0.
fn decode_jpeg_ls(
    h: &Header,
    fragments: &[Vec<u8>],
    offsets: &[u32],
    total: usize,
) -> Result<(Vec<u32>, Layout), IoError> {
    let path = h.path.as_path();
    let fail = |e: String| {
        invalid(
            path,
            format!("cannot decode {} pixel data: {e}", ts_name(&h.ts)),
        )
    };
    if h.bits_allocated != 8 && h.bits_allocated != 16 {
        return Err(fail(
            "BitsAllocated other than 8 or 16 is not supported".into(),
        ));
    }
    let spp = usize::from(h.samples_per_pixel);
    let frames = jpeg::frames(path, fragments, offsets, h.frames)?;
    let mut data = Vec::new();
    for f in &frames {
        data.extend(jpegls::decode(f, h.rows * h.cols * spp).map_err(fail)?);
    }
    let layout = Layout {
        photometric: if spp == 3 { "RGB" } else { &h.photometric }.to_string(),
        planar: false,
    };
    let bytes = usize::from(h.bits_allocated.div_ceil(8));
    Ok((bytes_to_words(&data, bytes, false, total), layout))
}

/// Whether a transfer syntax is one of JPEG's (baseline, extended, lossless).
fn is_jpeg(ts: &str) -> bool {
    ts.starts_with("1.2.840.10008.1.2.4.5") || ts.starts_with("1.2.840.10008.1.2.4.7")
}

/// Decodes encapsulated pixel data with dicom-pixeldata, or the JPEG frames it does
/// not decode as pydicom does with [`jpeg`]. The decoders allocate by the image size
/// their codestream declares and copy into a buffer sized by Rows and Columns (a larger
/// codestream panics in dicom-transfer-syntax-registry 0.10), so each codestream header
/// is checked first.
fn decode(
    h: &Header,
    obj: &FileDicomObject<InMemDicomObject>,
    total: usize,
) -> Result<(Vec<u32>, Layout), IoError> {
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
    let spp = usize::from(h.samples_per_pixel);
    let pixels = h.rows * h.cols;
    if h.ts == RLE_LOSSLESS {
        for fragment in seq.fragments() {
            check_rle(
                path,
                fragment,
                usize::from(h.bits_allocated / 8) * spp,
                pixels,
            )?;
        }
    } else if is_jpeg(&h.ts) {
        for fragment in seq.fragments() {
            check_codestream(path, &h.ts, fragment, pixels * spp, h.samples_per_pixel)?;
        }
        let frames = jpeg::frames(path, seq.fragments(), seq.offset_table(), h.frames)?;
        if let Some(own) = frames
            .first()
            .and_then(|f| jpeg::own_decoder(f, &h.photometric))
        {
            let mut words = Vec::with_capacity(total);
            for f in &frames {
                words.extend(jpeg::decode_frame(path, own, f, pixels, spp)?);
            }
            let layout = Layout {
                photometric: if spp == 3 { "RGB" } else { "MONOCHROME2" }.into(),
                planar: false,
            };
            return Ok((words, layout));
        }
    } else {
        // JPEG 2000 and JPEG-LS: a frame's codestream may span fragments (and follow
        // empty ones), so the headers are looked for in all of them together.
        let all: Vec<u8> = seq.fragments().iter().flatten().copied().collect();
        check_codestream(path, &h.ts, &all, pixels * spp, h.samples_per_pixel)?;
        if jpegls::is_jpeg_ls(&h.ts) {
            return decode_jpeg_ls(h, seq.fragments(), seq.offset_table(), total);
        }
    }
    // Backstop for decoder panics the checks above do not foresee (found by fuzzing or
    // not): a malformed file is an error, not an abort. The buffers are dropped on
    // unwind, nothing shared is left half-updated.
    let decoded =
        std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| obj.decode_pixel_data()))
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
    let layout = Layout {
        photometric: decoded.photometric_interpretation().as_str().to_string(),
        planar: decoded.planar_configuration() as u16 == 1,
    };
    let bytes = usize::from(decoded.bits_allocated().div_ceil(8)).max(1);
    let data = decoded.into_data();
    Ok((bytes_to_words(&data, bytes, false, total), layout))
}

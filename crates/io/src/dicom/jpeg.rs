//! The JPEG frames dicom-pixeldata does not decode as pydicom does, decoded here with
//! `libjpeg-turbo-rs`, a Rust reimplementation of libjpeg-turbo 3 (its samples equal C
//! libjpeg-turbo 3.1's on all 332 DCT frames of pydicom's corpora and the fixtures, 8 and
//! 12-bit, with and without the component-id rewrite below, checked when it replaced
//! the C library; the corpus tests check them against pydicom):
//!
//! - 12-bit lossy JPEG (extended, process 4: DICOM's JPEG Extended transfer syntax
//!   1.2.840.10008.1.2.4.51): jpeg-decoder reads 8-bit DCT only. The C library was built
//!   with CMake, which the default build must not need (issue 39).
//! - 3-component JPEG whose PhotometricInterpretation is RGB and whose codestream says
//!   nothing of its colour space (no JFIF APP0, no Adobe APP14, component ids other
//!   than 'R','G','B'): a JPEG decoder then assumes YCbCr and converts (T.872 / libjpeg's
//!   rule), but DICOM (PS3.5 8.2.1) and pydicom take the components as RGB already.
//!   The frame's component ids are rewritten to 'R','G','B' in a copy (libjpeg's own
//!   sign of RGB, jdapimin.c `default_decompress_parms`) and the frame decodes
//!   without a colour transform. (jpeg-decoder 0.3's `ColorTransform::None` was tried
//!   first: it differs from pydicom's decode by up to 110 on 4% of the samples of
//!   pydicom's SC_rgb_jpeg.dcm, where libjpeg-turbo differs by at most 1.)
//!
//! A sequential frame whose scan header has Ss, Se, Ah or Al other than 0, 63, 0, 0
//! (T.81 B.2.3) is refused, as C libjpeg-turbo's TurboJPEG API refused it (its warning
//! "Invalid SOS parameters for sequential JPEG", an error there) and pydicom does;
//! libjpeg-turbo-rs decodes it.

use std::path::Path;

use super::invalid;
use crate::IoError;

/// Which decoder a JPEG frame needs, if not dicom-pixeldata's.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Own {
    /// 12-bit DCT.
    Twelve,
    /// RGB components without a colour-space marker: decoded without a transform.
    Untransformed,
}

/// The markers of a JPEG codestream before its first scan that decide the decoder.
#[derive(Debug, Default)]
struct Markers {
    /// Sample precision and component ids of the first frame header (SOFn).
    precision: Option<u8>,
    lossless: bool,
    ids: Vec<u8>,
    jfif: bool,
    adobe: bool,
}

/// Walks the marker segments up to the first SOS (ITU T.81 B.1.1.4: every marker up to
/// the scan is followed by a two-byte length).
fn markers(data: &[u8]) -> Markers {
    let mut m = Markers::default();
    let mut i = 2; // after SOI
    while i + 4 <= data.len() && data[i] == 0xFF {
        let kind = data[i + 1];
        if kind == 0xFF {
            i += 1; // fill byte
            continue;
        }
        let len = usize::from(u16::from_be_bytes([data[i + 2], data[i + 3]]));
        let seg = data.get(i + 4..i + 2 + len).unwrap_or_default();
        match kind {
            0xE0 if seg.starts_with(b"JFIF\0") => m.jfif = true,
            // A complete APP14 (T.872 6.5.3: 12 bytes); libjpeg ignores a shorter one.
            0xEE if seg.len() >= 12 && seg.starts_with(b"Adobe") => m.adobe = true,
            0xC0..=0xCF if ![0xC4, 0xC8, 0xCC].contains(&kind) && m.precision.is_none() => {
                m.precision = seg.first().copied();
                m.lossless = matches!(kind, 0xC3 | 0xC7 | 0xCB | 0xCF);
                let n = usize::from(seg.get(5).copied().unwrap_or(0));
                m.ids = (0..n).filter_map(|c| seg.get(6 + 3 * c).copied()).collect();
            }
            0xDA => break,
            _ => {}
        }
        i += 2 + len;
    }
    m
}

/// Whether a frame (the first of the pixel data) needs one of the decoders here.
pub(super) fn own_decoder(frame: &[u8], photometric: &str) -> Option<Own> {
    let m = markers(frame);
    if m.precision == Some(12) && !m.lossless {
        return Some(Own::Twelve);
    }
    let rgb_ids = m.ids == [b'R', b'G', b'B'] || m.ids == [b'r', b'g', b'b'];
    (m.precision == Some(8)
        && !m.lossless
        && m.ids.len() == 3
        && photometric == "RGB"
        && !m.jfif
        && !m.adobe
        && !rgb_ids)
        .then_some(Own::Untransformed)
}

/// Decodes one frame with the decoder `own` names: `pixels` (Rows x Columns) samples of
/// `comps` components, interleaved, as u32 words.
pub(super) fn decode_frame(
    path: &Path,
    own: Own,
    frame: &[u8],
    pixels: usize,
    comps: usize,
) -> Result<Vec<u32>, IoError> {
    if !sequential_scans_valid(frame) {
        let what = if own == Own::Twelve {
            "a 12-bit JPEG frame"
        } else {
            "a JPEG frame"
        };
        return Err(invalid(
            path,
            format!("{what}: Invalid SOS parameters for sequential JPEG"),
        ));
    }
    let words = match own {
        Own::Twelve => turbo::decode(path, frame, comps, 12)?,
        Own::Untransformed => turbo::decode(path, &with_rgb_ids(frame), comps, 8)?,
    };
    if words.len() != pixels * comps {
        return Err(invalid(
            path,
            format!(
                "a JPEG frame decodes to {} samples, Rows x Columns x SamplesPerPixel is {}",
                words.len(),
                pixels * comps
            ),
        ));
    }
    Ok(words)
}

/// Whether every scan header (SOS) of a sequential DCT frame has Ss = 0, Se = 63 and
/// Ah = Al = 0 (T.81 B.2.3); progressive and lossless frames pass. A byte scan finds
/// every marker, as in [`with_rgb_ids`].
fn sequential_scans_valid(frame: &[u8]) -> bool {
    let mut sequential = false;
    for i in 0..frame.len().saturating_sub(1) {
        if frame[i] != 0xFF {
            continue;
        }
        match frame[i + 1] {
            0xC0 | 0xC1 | 0xC5 | 0xC9 | 0xCD => sequential = true,
            0xDA if sequential => {
                let n = usize::from(frame.get(i + 4).copied().unwrap_or(0));
                let tail = frame.get(i + 5 + 2 * n..i + 8 + 2 * n);
                if tail != Some(&[0, 63, 0][..]) {
                    return false;
                }
            }
            _ => {}
        }
    }
    true
}

/// A copy of a frame whose component ids (in every frame header and scan header) are
/// 'R', 'G', 'B' in component order. Entropy-coded data holds no FF followed by a
/// marker code other than RSTn (T.81 B.1.1.2), so a byte scan finds every SOFn and SOS.
fn with_rgb_ids(frame: &[u8]) -> Vec<u8> {
    let mut out = frame.to_vec();
    let mut ids: Vec<u8> = Vec::new();
    let mut i = 0;
    while i + 4 < out.len() {
        if out[i] != 0xFF {
            i += 1;
            continue;
        }
        let kind = out[i + 1];
        let body = i + 4;
        if (0xC0..=0xCF).contains(&kind) && ![0xC4, 0xC8, 0xCC].contains(&kind) {
            let n = usize::from(out.get(body + 5).copied().unwrap_or(0));
            for c in 0..n.min(3) {
                if let Some(id) = out.get_mut(body + 6 + 3 * c) {
                    ids.push(*id);
                    *id = b"RGB"[c];
                }
            }
        } else if kind == 0xDA {
            let n = usize::from(out.get(body).copied().unwrap_or(0));
            for c in 0..n {
                if let Some(id) = out.get_mut(body + 1 + 2 * c) {
                    if let Some(k) = ids.iter().position(|x| x == id) {
                        *id = b"RGB"[k.min(2)];
                    }
                }
            }
        }
        i += 2;
    }
    out
}

/// libjpeg-turbo's decoding, reimplemented in Rust (`libjpeg-turbo-rs`).
mod turbo {
    use std::path::Path;

    use libjpeg_turbo_rs as lj;

    use super::invalid;
    use crate::IoError;

    /// Decodes a frame of `comps` components (1 grey, 3 colour converted to RGB as
    /// libjpeg does) and `precision` bits (8 or 12) to interleaved words.
    pub(super) fn decode(
        path: &Path,
        frame: &[u8],
        comps: usize,
        precision: u8,
    ) -> Result<Vec<u32>, IoError> {
        let what = if precision == 12 {
            "a 12-bit JPEG frame"
        } else {
            "a JPEG frame"
        };
        let fail = |e: lj::JpegError| {
            invalid(
                path,
                format!("{what}: {}", super::super::one_line(&e.to_string())),
            )
        };
        if precision == 8 {
            let format = if comps == 1 {
                lj::PixelFormat::Grayscale
            } else {
                lj::PixelFormat::Rgb
            };
            let image = lj::decompress_to(frame, format).map_err(fail)?;
            return Ok(image.data.into_iter().map(u32::from).collect());
        }
        let image = lj::decompress_12bit(frame).map_err(fail)?;
        if image.num_components != comps {
            return Err(invalid(
                path,
                format!(
                    "{what} of {} components, SamplesPerPixel is {comps}",
                    image.num_components
                ),
            ));
        }
        // 12-bit samples are 0..4095: non-negative in an i16.
        Ok(image.data.into_iter().map(|x| x.max(0) as u32).collect())
    }
}

/// The frames of encapsulated pixel data (PS3.5 A.4): one fragment each when there are
/// as many fragments as frames; all fragments together for a single frame; else split
/// by the Basic Offset Table. Empty fragments contribute nothing.
pub(super) fn frames(
    path: &Path,
    fragments: &[Vec<u8>],
    offsets: &[u32],
    count: usize,
) -> Result<Vec<Vec<u8>>, IoError> {
    let nonempty: Vec<&Vec<u8>> = fragments.iter().filter(|f| !f.is_empty()).collect();
    if nonempty.len() == count {
        return Ok(nonempty.into_iter().cloned().collect());
    }
    if count == 1 {
        return Ok(vec![nonempty.into_iter().flatten().copied().collect()]);
    }
    if offsets.len() != count {
        return Err(invalid(
            path,
            format!(
                "{} fragments for {count} frames and no Basic Offset Table to split them",
                fragments.len()
            ),
        ));
    }
    // Offsets count bytes from the first fragment's item tag: each fragment takes its
    // 8-byte item header plus its length.
    let mut starts = Vec::with_capacity(fragments.len());
    let mut at = 0u64;
    for f in fragments {
        starts.push(at);
        at += 8 + f.len() as u64;
    }
    let mut out = vec![Vec::new(); count];
    for (f, &start) in fragments.iter().zip(&starts) {
        let k = offsets
            .iter()
            .rposition(|&o| u64::from(o) <= start)
            .unwrap_or(0);
        out[k].extend_from_slice(f);
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// SOI, an optional APPn, SOF0 or SOF1 with 3 components of the given ids, SOS.
    fn stream(app: Option<(u8, &[u8])>, sof: u8, precision: u8, ids: [u8; 3]) -> Vec<u8> {
        let mut v = vec![0xFF, 0xD8];
        if let Some((kind, body)) = app {
            v.extend([0xFF, kind]);
            v.extend(((body.len() + 2) as u16).to_be_bytes());
            v.extend(body);
        }
        v.extend([0xFF, sof, 0, 17, precision, 0, 8, 0, 8, 3]);
        for id in ids {
            v.extend([id, 0x11, 0]);
        }
        v.extend([0xFF, 0xDA, 0, 2]);
        v
    }

    #[test]
    fn the_decoder_follows_precision_and_colour_markers() {
        let plain = stream(None, 0xC0, 8, [0, 1, 2]);
        assert_eq!(own_decoder(&plain, "RGB"), Some(Own::Untransformed));
        assert_eq!(own_decoder(&plain, "YBR_FULL_422"), None);
        let jfif = stream(Some((0xE0, b"JFIF\0\x01\x02")), 0xC0, 8, [1, 2, 3]);
        assert_eq!(own_decoder(&jfif, "RGB"), None);
        let adobe = stream(Some((0xEE, b"Adobe\0\x64\0\0\0\0\x01")), 0xC0, 8, [1, 2, 3]);
        assert_eq!(own_decoder(&adobe, "RGB"), None);
        // A cut APP14 (pydicom's SC_rgb_jpeg.dcm) says nothing.
        let cut = stream(Some((0xEE, b"Adobe\0\0\0\0\0")), 0xC0, 8, [0, 1, 2]);
        assert_eq!(own_decoder(&cut, "RGB"), Some(Own::Untransformed));
        let rgb_ids = stream(None, 0xC0, 8, *b"RGB");
        assert_eq!(own_decoder(&rgb_ids, "RGB"), None);
        let twelve = stream(None, 0xC1, 12, [1, 2, 3]);
        assert_eq!(own_decoder(&twelve, "MONOCHROME2"), Some(Own::Twelve));
        let lossless12 = stream(None, 0xC3, 12, [1, 2, 3]);
        assert_eq!(own_decoder(&lossless12, "MONOCHROME2"), None);
    }

    #[test]
    fn component_ids_are_rewritten_in_frame_and_scan_headers() {
        let v = with_rgb_ids(&stream(None, 0xC0, 8, [0, 1, 2]));
        let sof = v.windows(2).position(|w| w == [0xFF, 0xC0]).unwrap();
        assert_eq!([v[sof + 10], v[sof + 13], v[sof + 16]], *b"RGB");
        let mut scan = stream(None, 0xC0, 8, [0, 1, 2]);
        scan.truncate(scan.len() - 4);
        scan.extend([0xFF, 0xDA, 0, 12, 3, 0, 0, 1, 0x11, 2, 0x11, 0, 63, 0]);
        let v = with_rgb_ids(&scan);
        let sos = v.windows(2).position(|w| w == [0xFF, 0xDA]).unwrap();
        assert_eq!([v[sos + 5], v[sos + 7], v[sos + 9]], *b"RGB");
    }

    #[test]
    fn fragments_become_frames() {
        let p = Path::new("x.dcm");
        let f = |n: u8, len: usize| vec![n; len];
        // One frame over an empty fragment and two more.
        let frags = vec![Vec::new(), f(1, 3), f(2, 2)];
        assert_eq!(
            frames(p, &frags, &[], 1).unwrap(),
            vec![vec![1, 1, 1, 2, 2]]
        );
        // One fragment a frame.
        assert_eq!(
            frames(p, &[f(1, 2), f(2, 2)], &[], 2).unwrap(),
            vec![f(1, 2), f(2, 2)]
        );
        // Two frames over three fragments, split by the offset table: frame 1 starts at
        // the third fragment (offsets 0, 8 + 2 + 8 + 2 = 20).
        let frags = vec![f(1, 2), f(1, 2), f(2, 4)];
        assert_eq!(
            frames(p, &frags, &[0, 20], 2).unwrap(),
            vec![f(1, 4), f(2, 4)]
        );
        assert!(frames(p, &frags, &[], 2).is_err());
    }
}

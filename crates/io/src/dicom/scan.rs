//! Opening a DICOM file: its layout (PS3.10 file, no preamble, bare data set), a walk
//! over every element header that bounds what dicom-rs will allocate and how deeply it
//! will recurse, and the parse itself.
//!
//! dicom-rs sizes a value buffer by the declared length before reading it (a 184-byte
//! file declaring a 0xF0000000-byte element costs 3.9 GB) and builds nested sequences
//! recursively (10,000 nested sequences overflow the stack). dicom-parser offers neither
//! a length nor a depth limit, hence this hand-written walk: it follows the encoding the
//! way dicom-parser 0.10 does (unknown VRs read as UN, any undefined-length element other
//! than encapsulated pixel data read as a sequence) and refuses a length longer than the
//! bytes left, or a nesting deeper than [`MAX_NESTING`], before dicom-rs sees the file.

use std::io::Read;
use std::path::Path;

use dicom_core::dictionary::{DataDictionary, DataDictionaryEntry};
use dicom_core::{Tag, VR};
use dicom_dictionary_std::{tags, StandardDataDictionary};
use dicom_encoding::TransferSyntaxIndex;
use dicom_object::{
    file::ReadPreamble, FileDicomObject, FileMetaTableBuilder, InMemDicomObject, OpenFileOptions,
};
use dicom_transfer_syntax_registry::TransferSyntaxRegistry;

use super::{invalid, one_line};
use crate::IoError;

/// Deepest nesting of sequences and items accepted (each sequence and each item is one
/// level, so 32 nested sequences). Enhanced multi-frame objects, the deepest common
/// case, use 4 to 6 levels (PS3.3 C.7.6.16); dicom-rs recurses once per level.
pub const MAX_NESTING: usize = 64;

/// The largest expansion of a deflate stream, 1032:1 (zlib technical details,
/// <https://zlib.net/zlib_tech.html>): a deflated data set is inflated for the walk up
/// to this many times its compressed size, and no further.
const DEFLATE_MAX_RATIO: u64 = 1032;

/// Explicit-VR VRs whose header has a 16-bit length (PS3.5 7.1.2, Table 7.1-2); every
/// other VR, and any VR dicom-rs does not know (read as UN), has two reserved bytes and a
/// 32-bit length.
const SHORT_VRS: [VR; 21] = [
    VR::AE,
    VR::AS,
    VR::AT,
    VR::CS,
    VR::DA,
    VR::DS,
    VR::DT,
    VR::FL,
    VR::FD,
    VR::IS,
    VR::LO,
    VR::LT,
    VR::PN,
    VR::SH,
    VR::SL,
    VR::SS,
    VR::ST,
    VR::TM,
    VR::UI,
    VR::UL,
    VR::US,
];

const UNDEFINED: u32 = u32::MAX;
const IMPLICIT_LE: &str = "1.2.840.10008.1.2";
const EXPLICIT_LE: &str = "1.2.840.10008.1.2.1";
const EXPLICIT_BE: &str = "1.2.840.10008.1.2.2";
const DEFLATED: &str = "1.2.840.10008.1.2.1.99";

/// How a data set is encoded.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Encoding {
    explicit: bool,
    big_endian: bool,
}

impl Encoding {
    fn of(ts: &str) -> Encoding {
        Encoding {
            explicit: ts != IMPLICIT_LE,
            big_endian: ts == EXPLICIT_BE,
        }
    }
    fn u16(self, b: &[u8]) -> u16 {
        let a = [b[0], b[1]];
        if self.big_endian {
            u16::from_be_bytes(a)
        } else {
            u16::from_le_bytes(a)
        }
    }
    fn u32(self, b: &[u8]) -> u32 {
        let a = [b[0], b[1], b[2], b[3]];
        if self.big_endian {
            u32::from_be_bytes(a)
        } else {
            u32::from_le_bytes(a)
        }
    }
}

/// Where the data set starts and how the file is laid out.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Layout {
    /// PS3.10: 128-byte preamble, "DICM", file meta group.
    Part10,
    /// "DICM" and the meta group without the preamble.
    NoPreamble,
    /// A bare data set (no preamble, no marker, no meta group) in this encoding.
    Bare(&'static str),
}

/// A parsed file and what was assumed to read it.
pub(crate) struct Loaded {
    /// The object; a bare data set gets a meta group naming the guessed syntax.
    pub obj: FileDicomObject<InMemDicomObject>,
    /// What was assumed, for the notes.
    pub notes: Vec<String>,
    /// Bytes in the file, or in the inflated data set of a deflated file: what any
    /// pixel data must fit in.
    pub data_len: u64,
    /// Whether the data set has PixelData at its top level.
    pub has_pixels: bool,
}

/// Reads, checks and parses a DICOM file; stops before the pixel data unless `pixels`.
/// `strict` refuses what is otherwise read with a note: no preamble, no meta group, no
/// TransferSyntaxUID, an implicit-VR data set under an explicit-VR syntax, a meta group
/// dicom-rs cannot parse.
pub(crate) fn load(path: &Path, pixels: bool, strict: bool) -> Result<Loaded, IoError> {
    let bytes = std::fs::read(path).map_err(|e| crate::link::os_error(path, e))?;
    let layout = layout(path, &bytes, strict)?;
    let mut notes = Vec::new();
    let lenient = |what: String, notes: &mut Vec<String>| {
        if strict {
            return Err(IoError::Invalid {
                path: path.into(),
                what: format!("{what} (--strict)"),
            });
        }
        notes.push(what);
        Ok(())
    };
    let (data_start, declared) = match layout {
        Layout::Part10 => walk_meta(path, &bytes, 132)?,
        Layout::NoPreamble => {
            notes.push("no 128-byte preamble before \"DICM\"".into());
            walk_meta(path, &bytes, 4)?
        }
        Layout::Bare(ts) => {
            notes.push(format!(
                "no preamble and no file meta group: read as a bare data set in {}",
                ts_name(ts)
            ));
            (0, Some(ts.to_string()))
        }
    };
    let data = &bytes[data_start..];
    // Parse with dicom-rs's own Part 10 reader unless the meta group needs help.
    let mut own_parse = matches!(layout, Layout::Bare(_));
    let ts = match declared {
        Some(ts) => ts,
        None => {
            let guess = guess_bare(data)
                .ok_or_else(|| invalid(path, "the file meta group has no TransferSyntaxUID"))?;
            lenient(
                format!(
                    "no TransferSyntaxUID in the file meta group: {} guessed from the data set",
                    ts_name(guess)
                ),
                &mut notes,
            )?;
            own_parse = true;
            guess.to_string()
        }
    };
    if TransferSyntaxRegistry.get(&ts).is_none() {
        return Err(IoError::Unsupported {
            path: path.into(),
            what: format!("unknown transfer syntax {}", one_line(&ts)),
        });
    }
    // The encoding the data set is parsed with: the syntax's, except that an explicit
    // little endian syntax over an implicit-VR data set (no valid VR after the first
    // tag) is read as implicit VR, as pydicom does.
    let mut encoding = encoding_uid(&ts);
    if encoding == EXPLICIT_LE && ts != DEFLATED && guess_bare(data) == Some(IMPLICIT_LE) {
        lenient(
            format!(
                "transfer syntax {} but an implicit VR data set: read as implicit VR",
                ts_name(&ts)
            ),
            &mut notes,
        )?;
        encoding = IMPLICIT_LE;
        own_parse = true;
    }
    let (data_len, has_pixels) = if ts == DEFLATED {
        let inflated = inflate(path, data)?;
        let has = walk(path, &inflated, Encoding::of(EXPLICIT_LE))?;
        (inflated.len() as u64, has)
    } else {
        let has = walk(path, data, Encoding::of(encoding))?;
        (bytes.len() as u64, has)
    };
    let obj = if own_parse {
        parse_data_set(path, data, &ts, encoding)?
    } else {
        match parse_part10(&bytes, layout, pixels) {
            Err(e @ dicom_object::ReadError::ParseMetaDataSet { .. }) if !strict => {
                notes.push(format!(
                    "file meta group not parsed ({}): data set read as {}",
                    one_line(&super::chain(&e)),
                    ts_name(&ts)
                ));
                parse_data_set(path, data, &ts, encoding)?
            }
            other => other.map_err(|e| super::open_error(path, e))?,
        }
    };
    Ok(Loaded {
        obj,
        notes,
        data_len,
        has_pixels,
    })
}

/// The UID of the native syntax a transfer syntax's data set is encoded in.
fn encoding_uid(ts: &str) -> &'static str {
    match ts {
        IMPLICIT_LE => IMPLICIT_LE,
        EXPLICIT_BE => EXPLICIT_BE,
        _ => EXPLICIT_LE,
    }
}

fn parse_part10(
    bytes: &[u8],
    layout: Layout,
    pixels: bool,
) -> Result<FileDicomObject<InMemDicomObject>, dicom_object::ReadError> {
    let mut o = OpenFileOptions::new().read_preamble(if layout == Layout::Part10 {
        ReadPreamble::Always
    } else {
        ReadPreamble::Never
    });
    if !pixels {
        o = o.read_until(tags::PIXEL_DATA);
    }
    o.from_reader(bytes)
}

/// Parses a data set in `encoding` and gives it a meta group naming `ts` (the syntax
/// its pixel data is decoded with).
fn parse_data_set(
    path: &Path,
    data: &[u8],
    ts: &str,
    encoding: &str,
) -> Result<FileDicomObject<InMemDicomObject>, IoError> {
    let syntax = TransferSyntaxRegistry
        .get(encoding)
        .expect("the native syntaxes are registered");
    let obj = InMemDicomObject::read_dataset_with_ts(data, syntax)
        .map_err(|e| super::open_error(path, e))?;
    let meta = FileMetaTableBuilder::new()
        .transfer_syntax(ts)
        // Placeholders, replaced by the data set's SOPClassUID and SOPInstanceUID when
        // it has them (with_meta); 1.2.840.10008.5.1.4.1.1.7 is Secondary Capture.
        .media_storage_sop_class_uid("1.2.840.10008.5.1.4.1.1.7")
        .media_storage_sop_instance_uid("2.25.0");
    obj.with_meta(meta)
        .map_err(|e| invalid(path, one_line(&super::chain(&e))))
}

/// The file's layout; without the preamble or the meta group, the encoding is guessed
/// from the first element as pydicom does with `force=True`: a plausible explicit VR
/// after the tag means explicit VR, and the byte order that gives the smaller group
/// number (data sets start with low groups) wins.
fn layout(path: &Path, bytes: &[u8], strict: bool) -> Result<Layout, IoError> {
    if bytes.len() >= 132 && &bytes[128..132] == b"DICM" {
        return Ok(Layout::Part10);
    }
    let refuse = |what: &str| IoError::BadMagic {
        path: path.into(),
        format: "DICOM",
        what: what.into(),
    };
    if bytes.starts_with(b"DICM") {
        if strict {
            return Err(refuse("no 128-byte preamble before \"DICM\" (--strict)"));
        }
        return Ok(Layout::NoPreamble);
    }
    if strict {
        return Err(refuse(
            "no \"DICM\" marker after the 128-byte preamble (--strict)",
        ));
    }
    guess_bare(bytes).map(Layout::Bare).ok_or_else(|| {
        refuse("no \"DICM\" marker after the 128-byte preamble, and no data set at the start")
    })
}

fn guess_bare(bytes: &[u8]) -> Option<&'static str> {
    if bytes.len() < 8 {
        return None;
    }
    let (le, be) = (
        u16::from_le_bytes([bytes[0], bytes[1]]),
        u16::from_be_bytes([bytes[0], bytes[1]]),
    );
    let explicit = VR::from_binary([bytes[4], bytes[5]]).is_some();
    // The first element of a data set is in a low group (0008 for nearly every object);
    // the other byte order reads it as 0x0800 or more.
    let group = le.min(be);
    if group == 0 || group > 0x0010 {
        return None;
    }
    Some(match (explicit, le <= be) {
        (true, true) => EXPLICIT_LE,
        (true, false) => EXPLICIT_BE,
        (false, true) => IMPLICIT_LE,
        // Implicit VR big endian was never a DICOM transfer syntax.
        (false, false) => return None,
    })
}

/// A readable name for a transfer syntax UID.
pub(crate) fn ts_name(uid: &str) -> String {
    let uid = uid.trim_end_matches(['\0', ' ']);
    match TransferSyntaxRegistry.get(uid) {
        Some(ts) => format!("{} ({uid})", ts.name()),
        None => one_line(uid),
    }
}

fn too_long(path: &Path, tag: Tag, declared: u64, left: usize) -> IoError {
    IoError::Truncated {
        path: path.into(),
        what: format!("element {tag} declares {declared} bytes, only {left} are left in the file"),
    }
}

/// Walks the file meta group (explicit VR little endian, group 0002); returns where the
/// data set starts and the transfer syntax UID, if given.
fn walk_meta(path: &Path, bytes: &[u8], start: usize) -> Result<(usize, Option<String>), IoError> {
    let le = Encoding::of(EXPLICIT_LE);
    let mut pos = start;
    let mut ts = None;
    while pos + 8 <= bytes.len() && le.u16(&bytes[pos..]) == 0x0002 {
        let (tag, _, len, header) = element_header(bytes, pos, le)
            .ok_or_else(|| truncated(path, "file meta group element header"))?;
        pos += header;
        let left = bytes.len() - pos;
        if len == UNDEFINED || len as usize > left {
            return Err(too_long(path, tag, len.into(), left));
        }
        if tag == tags::TRANSFER_SYNTAX_UID {
            let v = &bytes[pos..pos + len as usize];
            ts = Some(
                String::from_utf8_lossy(v)
                    .trim_end_matches(['\0', ' '])
                    .to_string(),
            );
        }
        pos += len as usize;
    }
    Ok((pos, ts.filter(|t| !t.is_empty())))
}

fn truncated(path: &Path, what: &str) -> IoError {
    IoError::Truncated {
        path: path.into(),
        what: format!("the file ends inside a {what}"),
    }
}

/// Decodes the element header at `pos`: (tag, VR, length, header size). `None` if the
/// bytes end inside it.
fn element_header(bytes: &[u8], pos: usize, enc: Encoding) -> Option<(Tag, VR, u32, usize)> {
    let b = bytes.get(pos..pos + 8)?;
    let tag = Tag(enc.u16(b), enc.u16(&b[2..]));
    if tag.0 == 0xFFFE {
        // Items and delimiters carry no VR in any encoding.
        return Some((tag, VR::UN, enc.u32(&b[4..]), 8));
    }
    if !enc.explicit {
        let vr = if tag == tags::PIXEL_DATA {
            VR::OW
        } else {
            StandardDataDictionary
                .by_tag(tag)
                .map(|e| e.vr().relaxed())
                .unwrap_or(VR::UN)
        };
        return Some((tag, vr, enc.u32(&b[4..]), 8));
    }
    let vr = VR::from_binary([b[4], b[5]]).unwrap_or(VR::UN);
    if SHORT_VRS.contains(&vr) {
        return Some((tag, vr, u32::from(enc.u16(&b[6..])), 8));
    }
    let l = bytes.get(pos + 8..pos + 12)?;
    Some((tag, vr, enc.u32(l), 12))
}

/// An open sequence or item of the walk, and where it ends (`None`: undefined length,
/// closed by a delimiter).
#[derive(Clone, Copy, Debug)]
struct Open {
    item: bool,
    end: Option<usize>,
}

/// Walks every element header of a data set, entering sequences and items, and refuses
/// a length beyond the end of the bytes or a nesting deeper than [`MAX_NESTING`].
/// Iterative: open sequences and items live on an explicit stack. Returns whether the
/// data set has PixelData at its top level.
///
/// The walk is dicom-parser 0.10's state machine (`DataSetReader::next`), so that it
/// sees the same elements dicom-rs will: right inside a sequence it reads item headers
/// (item, item delimiter, sequence delimiter); elsewhere element headers, where a
/// sequence VR or an undefined length opens a sequence, an item delimiter closes the
/// open item (and is ignored outside any), and any other tag, an item tag with a
/// defined length included, is an element whose value is skipped. Where dicom-parser
/// would stop with an error (an unexpected tag for an item header, a defined length
/// that ends before the bytes read), the walk stops too: dicom-rs reads nothing further.
/// (Two fuzzed files were read one way here and another by dicom-rs, which then
/// allocated 4 GB for a length the walk never saw: an item tag inside an item, and a
/// 38-byte UL value of which dicom-rs reads 36 bytes.)
fn walk(path: &Path, data: &[u8], enc: Encoding) -> Result<bool, IoError> {
    let mut open: Vec<Open> = Vec::new();
    let mut in_sequence = false;
    // `pos` is where dicom-parser's reader is in the bytes; `logical` is the position it
    // counts, which runs ahead where a binary value's length is not a multiple of its
    // sample size (see `consumed`). Ends of defined-length containers are counted in the
    // latter, as dicom-parser does.
    let mut pos = 0usize;
    let mut logical = 0usize;
    let mut has_pixels = false;
    let push = |open: &mut Vec<Open>, o: Open, tag: Tag| {
        open.push(o);
        if open.len() > MAX_NESTING {
            return Err(invalid(
                path,
                format!("sequences nested more than {MAX_NESTING} levels deep (at element {tag})"),
            ));
        }
        Ok(())
    };
    loop {
        // Containers of defined length end where their bytes do.
        while let Some(Open {
            item,
            end: Some(end),
        }) = open.last().copied()
        {
            if logical < end {
                break;
            }
            if logical > end {
                // dicom-parser: "inconsistent sequence end"; it reads no further.
                return Ok(has_pixels);
            }
            open.pop();
            in_sequence = item;
        }
        // dicom-rs ends the data set where no further tag can be read.
        let Some((tag, vr, len, header)) = element_header(data, pos, enc) else {
            return Ok(has_pixels);
        };
        pos += header;
        logical += header;
        let left = data.len() - pos;
        let defined = len != UNDEFINED;
        if defined && len as usize > left {
            return Err(too_long(path, tag, len.into(), left));
        }
        let end = defined.then_some(logical + len as usize);
        if in_sequence {
            match (tag.0, tag.1) {
                (0xFFFE, 0xE000) => {
                    in_sequence = false;
                    push(&mut open, Open { item: true, end }, tag)?;
                }
                (0xFFFE, 0xE00D) => {
                    open.pop();
                    in_sequence = true;
                }
                (0xFFFE, 0xE0DD) => {
                    open.pop();
                    in_sequence = false;
                }
                _ => return Ok(has_pixels),
            }
            continue;
        }
        has_pixels |= tag == tags::PIXEL_DATA && open.is_empty();
        match (tag.0, tag.1) {
            (0xFFFE, 0xE00D) => {
                if open.pop().is_some() {
                    in_sequence = true;
                }
            }
            _ if tag == tags::PIXEL_DATA && !defined => {
                let after = walk_fragments(path, data, pos, enc)?;
                logical += after - pos;
                pos = after;
            }
            _ if vr == VR::SQ || !defined => {
                in_sequence = true;
                push(&mut open, Open { item: false, end }, tag)?;
            }
            _ => {
                pos += consumed(vr, len as usize);
                logical += len as usize;
            }
        }
    }
}

/// The bytes dicom-parser 0.10 reads for a value of `len` bytes: binary numbers are read
/// as `len / size` whole values (stateful/decode.rs `read_value_ul` and the like), so a
/// length that is not a multiple of the size leaves the rest unread, and the next
/// header is read from there.
fn consumed(vr: VR, len: usize) -> usize {
    match vr {
        VR::US | VR::OW | VR::SS => len & !1,
        VR::AT | VR::UL | VR::OL | VR::SL | VR::FL | VR::OF => len & !3,
        VR::FD | VR::OD | VR::SV | VR::UV | VR::OV => len & !7,
        _ => len,
    }
}

/// Walks the fragments of encapsulated pixel data from `pos`; returns the offset after
/// the sequence delimiter (or the end of the data).
fn walk_fragments(
    path: &Path,
    data: &[u8],
    mut pos: usize,
    enc: Encoding,
) -> Result<usize, IoError> {
    while let Some(b) = data.get(pos..pos + 8) {
        let (tag, len) = (Tag(enc.u16(b), enc.u16(&b[2..])), enc.u32(&b[4..]));
        pos += 8;
        if tag == Tag(0xFFFE, 0xE0DD) {
            return Ok(pos);
        }
        let left = data.len() - pos;
        if tag != Tag(0xFFFE, 0xE000) || len as usize > left {
            if len == UNDEFINED || len as usize > left {
                return Err(too_long(path, tag, len.into(), left));
            }
            return Err(invalid(
                path,
                format!("element {tag} inside encapsulated pixel data, expected an item"),
            ));
        }
        pos += len as usize;
    }
    Ok(data.len())
}

/// Inflates a deflated data set (raw deflate, PS3.5 A.5) for the walk, at most
/// [`DEFLATE_MAX_RATIO`] times its size.
fn inflate(path: &Path, data: &[u8]) -> Result<Vec<u8>, IoError> {
    let cap = (data.len() as u64).saturating_mul(DEFLATE_MAX_RATIO);
    let mut out = Vec::new();
    flate2::read::DeflateDecoder::new(data)
        .take(cap)
        .read_to_end(&mut out)
        .map_err(|e| invalid(path, format!("corrupt deflated data set: {e}")))?;
    Ok(out)
}

//! Reading a GIFTI document: the file (gzip-compressed or not, with a cap on its
//! inflated size) into data arrays whose `<Data>` text is kept undecoded, and the label
//! table.

use std::io::Read;
use std::path::Path;

use quick_xml::events::Event;

use super::{invalid, Label};
use crate::common::{is_gzip, open, os_or_invalid};
use crate::IoError;

/// Largest XML document accepted (after gzip): far above a 1M-vertex surface in ASCII.
const MAX_XML_BYTES: u64 = 4 << 30;

/// Largest inflation accepted for a gzipped document (decompressed / compressed size).
const MAX_GZIP_RATIO: u64 = 64;

/// A gzipped document may always inflate to this many bytes, whatever its ratio.
const MIN_XML_CAP: u64 = 64 << 20;

/// Characters of `<Data>` text accepted per announced value (ASCII numbers with
/// separators, or base64 with line breaks, take far fewer), plus a fixed slack.
const DATA_CHARS_PER_VALUE: usize = 32;
const DATA_SLACK: usize = 1 << 16;

#[derive(Default, Debug)]
pub(super) struct DataArray {
    pub(super) intent: String,
    /// `ExternalFileName` and `ExternalFileOffset` (for ExternalFileBinary).
    pub(super) external: (String, String),
    /// `<MetaData>` name/value pairs.
    pub(super) meta: Vec<(String, String)>,
    pub(super) data_type: String,
    pub(super) column_major: bool,
    pub(super) dims: Vec<usize>,
    pub(super) encoding: String,
    pub(super) big_endian: bool,
    pub(super) data_space: Option<String>,
    pub(super) transformed_space: Option<String>,
    pub(super) matrix: Option<String>,
    pub(super) data: String,
    /// The `<Data>` text ran past what the dimensions allow; the rest was dropped.
    pub(super) overflow: bool,
}

impl DataArray {
    /// Most `<Data>` characters the announced dimensions can explain.
    pub(super) fn data_cap(&self) -> usize {
        self.dims
            .iter()
            .fold(1usize, |acc, &d| acc.saturating_mul(d))
            .saturating_mul(DATA_CHARS_PER_VALUE)
            .saturating_add(DATA_SLACK)
    }
}

/// The data arrays and the label table of a GIFTI file, not yet decoded.
pub(super) fn load(path: &Path) -> Result<(Vec<DataArray>, Vec<Label>), IoError> {
    let gz = is_gzip(path)?;
    let file = open(path)?;
    let file_len = file.metadata().map_err(|e| os_or_invalid(path, e))?.len();
    // A gzip bomb (a megabyte inflating to gigabytes of whitespace) is stopped at a
    // ratio no real surface reaches: base64 or ASCII numbers compress a few times, not
    // a hundred.
    let max_xml = if gz {
        file_len
            .saturating_mul(MAX_GZIP_RATIO)
            .clamp(MIN_XML_CAP, MAX_XML_BYTES)
    } else {
        MAX_XML_BYTES
    };
    let mut text = Vec::new();
    let reader: Box<dyn Read> = if gz {
        Box::new(flate2::read::MultiGzDecoder::new(std::io::BufReader::new(
            file,
        )))
    } else {
        Box::new(file)
    };
    reader
        .take(max_xml + 1)
        .read_to_end(&mut text)
        .map_err(|e| os_or_invalid(path, e))?;
    if text.len() as u64 > max_xml {
        return Err(IoError::TooLarge {
            path: path.into(),
            what: if gz {
                format!(
                    "the {file_len}-byte gzip file inflates past {max_xml} bytes of XML \
                     (more than {MAX_GZIP_RATIO}x: a decompression bomb?)"
                )
            } else {
                format!("XML larger than {MAX_XML_BYTES} bytes")
            },
        });
    }
    let text = String::from_utf8(text).map_err(|_| invalid(path, "the XML is not UTF-8"))?;
    parse_xml(path, &text)
}

/// What the XML walk has collected so far.
#[derive(Default)]
struct Collect {
    arrays: Vec<DataArray>,
    labels: Vec<Label>,
    current: Option<DataArray>,
    /// The innermost open elements, for attaching text.
    stack: Vec<String>,
    /// The `<Name>` and `<Value>` of the `<MD>` being read.
    md: (String, String),
}

fn parse_xml(path: &Path, text: &str) -> Result<(Vec<DataArray>, Vec<Label>), IoError> {
    let mut reader = quick_xml::Reader::from_str(text);
    let mut c = Collect::default();
    let mut saw_root = false;
    loop {
        let event = reader.read_event().map_err(|e| {
            invalid(
                path,
                format!("XML error at byte {}: {e}", reader.buffer_position()),
            )
        })?;
        match event {
            Event::Start(ref e) | Event::Empty(ref e) if e.local_name().as_ref() == "DataArray" => {
                let a = data_array(path, e)?;
                if matches!(event, Event::Empty(_)) {
                    c.arrays.push(a);
                } else {
                    c.current = Some(a);
                    c.stack.push("DataArray".into());
                }
            }
            Event::Start(ref e) | Event::Empty(ref e) if e.local_name().as_ref() == "Label" => {
                c.labels.push(label(path, e)?);
                if matches!(event, Event::Start(_)) {
                    c.stack.push("Label".into());
                }
            }
            Event::Start(e) => {
                let name = e.local_name().as_ref().to_string();
                if name == "GIFTI" {
                    saw_root = true;
                }
                if name == "MD" {
                    c.md = Default::default();
                }
                c.stack.push(name);
            }
            Event::End(e) => {
                match e.local_name().as_ref() {
                    "DataArray" => c.arrays.extend(c.current.take()),
                    "MD" => {
                        if let Some(a) = c.current.as_mut() {
                            a.meta.push(std::mem::take(&mut c.md));
                        }
                    }
                    _ => {}
                }
                c.stack.pop();
            }
            Event::Text(t) => add_text(&mut c, &t.xml10_content()),
            Event::CData(t) => add_text(&mut c, &t.xml10_content()),
            Event::Eof => break,
            _ => {}
        }
    }
    if !saw_root {
        return Err(IoError::BadMagic {
            path: path.into(),
            format: "GIFTI",
            what: "no <GIFTI> root element".into(),
        });
    }
    Ok((c.arrays, c.labels))
}

/// The attributes of an element as (local name, trimmed normalised value).
fn attributes(
    path: &Path,
    e: &quick_xml::events::BytesStart,
) -> Result<Vec<(String, String)>, IoError> {
    e.attributes()
        .map(|attr| {
            let attr = attr.map_err(|e| invalid(path, format!("XML attribute: {e}")))?;
            let value = attr
                .normalized_value(quick_xml::XmlVersion::Implicit1_0)
                .map_err(|e| invalid(path, format!("XML attribute: {e}")))?
                .trim()
                .to_string();
            let key = attr.key.local_name().as_ref().to_string();
            Ok((key, value))
        })
        .collect()
}

/// A `<DataArray>`'s attributes.
fn data_array(path: &Path, e: &quick_xml::events::BytesStart) -> Result<DataArray, IoError> {
    let mut a = DataArray::default();
    let mut dims = [None; 6];
    let mut dimensionality = None;
    for (key, value) in attributes(path, e)? {
        match key.as_str() {
            "Intent" => a.intent = value,
            "DataType" => a.data_type = value,
            "ArrayIndexingOrder" => a.column_major = value == "ColumnMajorOrder",
            "Encoding" => a.encoding = value,
            "Endian" => a.big_endian = value == "BigEndian",
            "ExternalFileName" => a.external.0 = value,
            "ExternalFileOffset" => a.external.1 = value,
            "Dimensionality" => dimensionality = Some(parse_usize(path, &value)?),
            k if k.len() == 4 && k.starts_with("Dim") && k.as_bytes()[3].is_ascii_digit() => {
                let i = (k.as_bytes()[3] - b'0') as usize;
                if i < 6 {
                    dims[i] = Some(parse_usize(path, &value)?);
                }
            }
            _ => {}
        }
    }
    let nd = dimensionality.ok_or_else(|| invalid(path, "a DataArray lacks Dimensionality"))?;
    if !(1..=6).contains(&nd) {
        return Err(invalid(path, format!("Dimensionality {nd} is not 1..6")));
    }
    a.dims = (0..nd)
        .map(|i| dims[i].ok_or_else(|| invalid(path, format!("a DataArray lacks Dim{i}"))))
        .collect::<Result<_, _>>()?;
    Ok(a)
}

/// A `<Label>`'s attributes (its name is the element's text, added later).
fn label(path: &Path, e: &quick_xml::events::BytesStart) -> Result<Label, IoError> {
    let mut l = Label {
        key: 0,
        name: String::new(),
        rgba: [0.0; 4],
    };
    for (key, value) in attributes(path, e)? {
        let channel = ["Red", "Green", "Blue", "Alpha"]
            .iter()
            .position(|&c| c == key);
        if key == "Key" || key == "Index" {
            l.key = value
                .parse()
                .map_err(|_| invalid(path, format!("label key '{value}' is not an integer")))?;
        } else if let Some(i) = channel {
            l.rgba[i] = value
                .parse()
                .map_err(|_| invalid(path, format!("label colour '{value}' is not a number")))?;
        }
    }
    Ok(l)
}

fn add_text(c: &mut Collect, s: &str) {
    let top = c.stack.last().map(String::as_str);
    if top == Some("Label") {
        if let Some(l) = c.labels.last_mut() {
            l.name.push_str(s.trim());
        }
        return;
    }
    let in_md = c.stack.len() >= 2 && c.stack[c.stack.len() - 2] == "MD";
    let Some(a) = c.current.as_mut() else { return };
    match top {
        Some("Data") => {
            if a.data.len().saturating_add(s.len()) > a.data_cap() {
                a.overflow = true;
            } else {
                a.data.push_str(s);
            }
        }
        Some("Name") if in_md => c.md.0.push_str(s.trim()),
        Some("Value") if in_md => c.md.1.push_str(s.trim()),
        Some("DataSpace") => a.data_space = Some(s.trim().to_string()),
        Some("TransformedSpace") => a.transformed_space = Some(s.trim().to_string()),
        Some("MatrixData") => a.matrix.get_or_insert_with(String::new).push_str(s),
        _ => {}
    }
}

fn parse_usize(path: &Path, s: &str) -> Result<usize, IoError> {
    s.parse()
        .map_err(|_| invalid(path, format!("'{s}' is not a dimension")))
}

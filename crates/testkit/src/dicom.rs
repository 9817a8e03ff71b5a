//! DICOM objects for tests: the header of an image (SOP, series, image pixel module)
//! that glint-io's and the CLI's DICOM tests add their geometry and pixels to, and the
//! writer of a file with its meta table.

use std::path::Path;

use dicom_core::value::PrimitiveValue;
use dicom_core::{DataElement, Tag, VR};
use dicom_dictionary_std::tags;
use dicom_object::{FileMetaTableBuilder, InMemDicomObject};

/// Explicit VR Little Endian.
pub const EXPLICIT_LE: &str = "1.2.840.10008.1.2.1";
/// Implicit VR Little Endian.
pub const IMPLICIT_LE: &str = "1.2.840.10008.1.2";
/// Explicit VR Big Endian (retired, still read).
pub const EXPLICIT_BE: &str = "1.2.840.10008.1.2.2";
/// CT Image Storage.
pub const CT_STORAGE: &str = "1.2.840.10008.5.1.4.1.1.2";
/// Multi-frame True Color Secondary Capture Image Storage (PS3.4 B.5).
pub const SC_TRUE_COLOR: &str = "1.2.840.10008.5.1.4.1.1.7.4";

/// The header of an image object: what identifies it and describes its pixels.
#[derive(Clone, Debug, PartialEq)]
pub struct ImageHeader {
    /// SOPClassUID.
    pub class: &'static str,
    /// SOPInstanceUID.
    pub instance: String,
    /// SeriesInstanceUID.
    pub series: String,
    /// Modality.
    pub modality: &'static str,
    /// Rows.
    pub rows: u16,
    /// Columns.
    pub columns: u16,
    /// NumberOfFrames, when the object has it.
    pub frames: Option<u32>,
    /// SamplesPerPixel.
    pub samples: u16,
    /// PhotometricInterpretation.
    pub photometric: &'static str,
    /// BitsAllocated and BitsStored (HighBit one less).
    pub bits: u16,
    /// PixelRepresentation 1 (two's complement) rather than 0.
    pub signed: bool,
}

impl ImageHeader {
    /// A CT image of `rows` x `columns` 16-bit unsigned grey samples (MONOCHROME2),
    /// series `1.2.3`, instance `1.2.3.4`, one frame.
    pub fn ct(rows: u16, columns: u16) -> ImageHeader {
        ImageHeader {
            class: CT_STORAGE,
            instance: "1.2.3.4".into(),
            series: "1.2.3".into(),
            modality: "CT",
            rows,
            columns,
            frames: None,
            samples: 1,
            photometric: "MONOCHROME2",
            bits: 16,
            signed: false,
        }
    }

    /// The header's elements in a new object.
    pub fn object(&self) -> InMemDicomObject {
        let mut o = InMemDicomObject::new_empty();
        let text = |s: &str| PrimitiveValue::from(s.to_string());
        let us = |v: u16| PrimitiveValue::from(v);
        put(&mut o, tags::SOP_CLASS_UID, VR::UI, text(self.class));
        put(&mut o, tags::SOP_INSTANCE_UID, VR::UI, text(&self.instance));
        put(
            &mut o,
            tags::SERIES_INSTANCE_UID,
            VR::UI,
            text(&self.series),
        );
        put(&mut o, tags::MODALITY, VR::CS, text(self.modality));
        put(&mut o, tags::ROWS, VR::US, us(self.rows));
        put(&mut o, tags::COLUMNS, VR::US, us(self.columns));
        if let Some(n) = self.frames {
            put(&mut o, tags::NUMBER_OF_FRAMES, VR::IS, text(&n.to_string()));
        }
        put(&mut o, tags::SAMPLES_PER_PIXEL, VR::US, us(self.samples));
        let photometric = text(self.photometric);
        put(
            &mut o,
            tags::PHOTOMETRIC_INTERPRETATION,
            VR::CS,
            photometric,
        );
        put(&mut o, tags::BITS_ALLOCATED, VR::US, us(self.bits));
        put(&mut o, tags::BITS_STORED, VR::US, us(self.bits));
        put(&mut o, tags::HIGH_BIT, VR::US, us(self.bits - 1));
        let representation = us(u16::from(self.signed));
        put(&mut o, tags::PIXEL_REPRESENTATION, VR::US, representation);
        o
    }
}

/// Puts (or replaces) one element.
pub fn put(obj: &mut InMemDicomObject, tag: Tag, vr: VR, value: PrimitiveValue) {
    obj.put(DataElement::new(tag, vr, value));
}

/// A decimal string (DS) value of several numbers.
pub fn ds(values: &[f64]) -> PrimitiveValue {
    PrimitiveValue::Strs(values.iter().map(|x| format!("{x}")).collect())
}

/// Writes `obj` to `path` as a DICOM file (preamble, meta table) of SOP class `class`
/// in the transfer syntax `ts`. Panics on failure: a test fixture that cannot be
/// written is a broken test.
pub fn write(path: &Path, obj: InMemDicomObject, class: &str, ts: &str) {
    let meta = FileMetaTableBuilder::new()
        .transfer_syntax(ts)
        .media_storage_sop_class_uid(class);
    obj.with_meta(meta)
        .expect("a complete meta table")
        .write_to_file(path)
        .expect("the fixture is written");
}

//! The colour table a DICOM Segmentation carries: its segments' numbers, labels and
//! recommended display colours (CIELab, converted to sRGB).

use std::path::Path;

use glint_io::dicom::{read_rois, read_segments, Roi, Segment};
use glint_io::{Format, ReadOptions};

use crate::table::{named_color, LabelEntry, LabelTable, OPAQUE};
use crate::LabelError;

/// The D65 white point (CIE XYZ, Y = 1). DICOM does not name the illuminant of
/// RecommendedDisplayCIELabValue; DCMTK (`IODCIELabUtil`), PixelMed (`ColorUtilities`)
/// and highdicom (`highdicom.color`) all convert with D65, sRGB's own white, so no
/// chromatic adaptation is needed; glint follows them.
const D65: [f64; 3] = [0.950_47, 1.0, 1.088_83];

/// CIE XYZ (D65) to linear sRGB, IEC 61966-2-1:1999 (the inverse of its RGB to XYZ
/// matrix, to the four decimals the standard gives).
const XYZ_TO_SRGB: [[f64; 3]; 3] = [
    [3.2406, -1.5372, -0.4986],
    [-0.9689, 1.8758, 0.0415],
    [0.0557, -0.2040, 1.0570],
];

/// A DICOM CIELab value as stored (PS3.3 C.10.7.1.1: L* 0..100 and a*, b* -128..127
/// scaled linearly to 0..65535) as an sRGB colour, clipped to the sRGB gamut.
pub fn cielab_to_srgb(stored: [u16; 3]) -> [u8; 3] {
    let scale = |v: u16, range: f64| f64::from(v) * range / 65535.0;
    let l = scale(stored[0], 100.0);
    let a = scale(stored[1], 255.0) - 128.0;
    let b = scale(stored[2], 255.0) - 128.0;
    // CIE 15:2004 (8.2.1.1), inverted: f^-1(t) = t^3 above 6/29, linear below.
    let delta: f64 = 6.0 / 29.0;
    let finv = |t: f64| {
        if t > delta {
            t.powi(3)
        } else {
            3.0 * delta * delta * (t - 4.0 / 29.0)
        }
    };
    let fy = (l + 16.0) / 116.0;
    let xyz = [fy + a / 500.0, fy, fy - b / 200.0]
        .iter()
        .zip(D65)
        .map(|(&f, w)| w * finv(f))
        .collect::<Vec<f64>>();
    XYZ_TO_SRGB.map(|row| {
        let c = (row[0] * xyz[0] + row[1] * xyz[1] + row[2] * xyz[2]).clamp(0.0, 1.0);
        // The sRGB transfer function (IEC 61966-2-1).
        let e = if c <= 0.003_130_8 {
            12.92 * c
        } else {
            1.055 * c.powf(1.0 / 2.4) - 0.055
        };
        (e * 255.0).round() as u8
    })
}

impl LabelTable {
    /// The table of a Segmentation's segments: SegmentNumber to SegmentLabel and the
    /// RecommendedDisplayCIELabValue as sRGB ([`cielab_to_srgb`]); a segment without a
    /// colour gets [`named_color`].
    pub fn from_segments(source: impl Into<String>, segments: &[Segment]) -> LabelTable {
        let mut table = LabelTable::new(source);
        for s in segments {
            let value = u32::from(s.number);
            let color = s
                .cielab
                .map(cielab_to_srgb)
                .unwrap_or_else(|| named_color(&s.label, value));
            table.insert(
                value,
                LabelEntry {
                    name: s.label.clone(),
                    color,
                    alpha: OPAQUE,
                },
            );
        }
        table
    }

    /// The table of an RT structure set's ROIs: ROINumber to ROIName and
    /// ROIDisplayColor; an ROI without a colour gets [`named_color`].
    pub fn from_rois(source: impl Into<String>, rois: &[Roi]) -> LabelTable {
        let mut table = LabelTable::new(source);
        for r in rois {
            let color = r.color.unwrap_or_else(|| named_color(&r.name, r.number));
            table.insert(
                r.number,
                LabelEntry {
                    name: r.name.clone(),
                    color,
                    alpha: OPAQUE,
                },
            );
        }
        table
    }

    /// The table a label map file carries itself: a DICOM Segmentation's segments
    /// ([`LabelTable::from_segments`]) or an RT structure set's ROIs
    /// ([`LabelTable::from_rois`]); `None` for any other file.
    pub fn embedded(path: &Path) -> Result<Option<LabelTable>, LabelError> {
        let guess = Format::guess(path);
        if !path.is_file() || guess.is_some_and(|f| f != Format::Dicom) {
            return Ok(None);
        }
        let options = ReadOptions::default();
        match read_segments(path, &options) {
            Ok(Some(s)) => Ok(Some(LabelTable::from_segments(
                format!("{} (DICOM SEG)", path.display()),
                &s,
            ))),
            Ok(None) => Ok(read_rois(path, &options)?.map(|r| {
                LabelTable::from_rois(format!("{} (RT structure set)", path.display()), &r)
            })),
            // A file without a DICOM extension that is not DICOM.
            Err(_) if guess.is_none() => Ok(None),
            Err(e) => Err(e.into()),
        }
    }

    /// The built-in table a label map file defaults to by its name: FreeSurfer's for
    /// `aseg`, `aparc` and `wmparc` files.
    pub fn default_for(path: &Path) -> Option<&'static str> {
        let name = path.file_name()?.to_string_lossy().to_ascii_lowercase();
        ["aseg", "aparc", "wmparc"]
            .iter()
            .any(|k| name.contains(k))
            .then_some("freesurfer")
    }

    /// The table that names the labels of the map at `path`, the one rule the
    /// renderer, the viewer's legend and `glint info` share: the table asked for (a
    /// built-in name or a file), else the one its file name implies
    /// ([`LabelTable::default_for`]), else the one the file carries
    /// ([`LabelTable::embedded`]), else an empty table whose names and colours are
    /// generated (source `generated`).
    pub fn for_map(path: &Path, table: Option<&str>) -> Result<LabelTable, LabelError> {
        match table.or_else(|| LabelTable::default_for(path)) {
            Some(t) => LabelTable::open(t),
            None => Ok(LabelTable::embedded(path)?.unwrap_or_else(|| LabelTable::new("generated"))),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_maps_table_is_the_one_asked_for_then_its_names_then_generated() {
        let dir = tempfile::tempdir().unwrap();
        let map = dir.path().join("mask.nii");
        std::fs::write(&map, b"not read: a NIfTI carries no table").unwrap();
        let aseg = dir.path().join("sub-01_aseg.nii.gz");
        std::fs::write(&aseg, b"").unwrap();
        assert_eq!(LabelTable::default_for(&aseg), Some("freesurfer"));
        assert_eq!(LabelTable::default_for(&map), None);
        let generated = LabelTable::for_map(&map, None).unwrap();
        assert_eq!(
            (generated.source.as_str(), generated.len()),
            ("generated", 0)
        );
        let by_name = LabelTable::for_map(&aseg, None).unwrap();
        assert_eq!(by_name.name_of(17), LabelTable::freesurfer().name_of(17));
        let asked = LabelTable::for_map(&aseg, Some("totalsegmentator")).unwrap();
        assert_eq!(asked.name_of(1), LabelTable::totalsegmentator().name_of(1));
        assert!(LabelTable::for_map(&map, Some("no-such-table")).is_err());
    }

    /// The stored DICOM value of a CIELab colour (PS3.3 C.10.7.1.1 scaling).
    fn stored(l: f64, a: f64, b: f64) -> [u16; 3] {
        [
            (l * 65535.0 / 100.0).round() as u16,
            ((a + 128.0) * 65535.0 / 255.0).round() as u16,
            ((b + 128.0) * 65535.0 / 255.0).round() as u16,
        ]
    }

    #[test]
    fn white_black_and_grey_are_neutral() {
        assert_eq!(cielab_to_srgb(stored(100.0, 0.0, 0.0)), [255, 255, 255]);
        assert_eq!(cielab_to_srgb(stored(0.0, 0.0, 0.0)), [0, 0, 0]);
        // L* 50 is Y = ((50 + 16) / 116)^3 = 0.1842, sRGB-encoded 0.4663 -> 119.
        assert_eq!(cielab_to_srgb(stored(50.0, 0.0, 0.0)), [119, 119, 119]);
    }

    #[test]
    fn values_written_by_highdicom_come_back_as_the_rgb_given() {
        // highdicom 0.28.2 `CIELabColor.from_rgb(r, g, b).value` for these colours.
        assert_eq!(cielab_to_srgb([41661, 41167, 40792]), [221, 130, 101]);
        assert_eq!(cielab_to_srgb([37352, 45282, 42259]), [224, 97, 76]);
        // Out of gamut (pure a* 127): clipped, not wrapped.
        let c = cielab_to_srgb([32768, 65535, 32896]);
        assert_eq!(c[0], 255);
    }

    #[test]
    fn segments_become_a_table() {
        let segments = [
            Segment {
                number: 2,
                label: "liver".into(),
                cielab: None,
            },
            Segment {
                number: 5,
                label: "Aorta".into(),
                cielab: Some([41661, 41167, 40792]),
            },
        ];
        let t = LabelTable::from_segments("seg", &segments);
        assert_eq!(t.len(), 2);
        assert_eq!(t.name_of(5), "Aorta");
        assert_eq!(t.color_of(5), [221, 130, 101]);
        // No colour: TotalSegmentator's for a class name.
        assert_eq!(t.color_of(2), named_color("liver", 2));
    }
}

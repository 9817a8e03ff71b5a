//! What a file holds, as `glint info` reports it: one value per file ([`FileInfo`]),
//! serialised for `--json` and written as text by its [`Display`]
//! form, so both outputs come from the same facts.

use std::fmt::{self, Display, Formatter};
use std::path::Path;

use serde::Serialize;
use serde_json::Value;

use crate::dicom::Listing;
use crate::{MeshFile, VertexData, VertexValues, VolumeFile};

/// What a volume, mesh or per-vertex data file holds.
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(untagged)]
pub enum FileInfo {
    /// A volume (with a DICOM directory's series and skipped files).
    Volume(Box<VolumeInfo>),
    /// A surface, or a GIFTI file of per-vertex data only.
    Mesh(MeshInfo),
}

/// A volume's facts.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct VolumeInfo {
    /// The path as given.
    pub file: String,
    /// `volume`.
    pub kind: &'static str,
    /// The format's name.
    pub format: &'static str,
    /// Samples along i, j, k.
    pub dims: [usize; 3],
    /// Samples in all.
    pub voxels: usize,
    /// Spacing along i, j, k, mm.
    pub spacing_mm: [f64; 3],
    /// The stored sample type.
    #[serde(rename = "type")]
    pub sample_type: &'static str,
    /// `value = slope · stored + intercept`.
    pub slope: f64,
    /// See `slope`.
    pub intercept: f64,
    /// The values' range (`null` where not finite).
    pub range: [Option<f64>; 2],
    /// The values' range as found (the text form writes `NaN` or `inf` as they are).
    #[serde(skip)]
    pub range_found: [f64; 2],
    /// The values' units, where the file says.
    pub units: Option<String>,
    /// Whether it is a colour volume (the range is of its grey samples).
    pub colour: bool,
    /// Voxel to RAS+ mm.
    pub affine_voxel_to_ras_mm: [[f64; 4]; 4],
    /// What the reader said.
    pub notes: Vec<String>,
    /// A DICOM directory's image series.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub series: Option<Vec<SeriesInfo>>,
    /// A DICOM directory's files not read as images.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub skipped: Option<Vec<SkippedInfo>>,
}

/// One image series of a DICOM directory.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SeriesInfo {
    /// SeriesInstanceUID.
    pub uid: String,
    /// Modality.
    pub modality: Option<String>,
    /// SeriesDescription.
    pub description: Option<String>,
    /// Files of the series.
    pub files: usize,
    /// Frames in all its files.
    pub slices: usize,
    /// Columns, rows, slices.
    pub dims: [usize; 3],
    /// Photometric interpretation.
    pub photometric: String,
}

/// A file of a DICOM directory not read as an image.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SkippedInfo {
    /// The file.
    pub file: String,
    /// Why (one line).
    pub reason: String,
    /// Its SOP class name.
    pub class: Option<String>,
    /// Its Modality.
    pub modality: Option<String>,
    /// Its SeriesInstanceUID.
    pub series: Option<String>,
}

/// A surface's facts, or a per-vertex data file's (no surface).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct MeshInfo {
    /// The path as given.
    pub file: String,
    /// `mesh`, or `vertex data` for a GIFTI file without a surface.
    pub kind: &'static str,
    /// The format's name.
    pub format: &'static str,
    /// The surface, `None` for per-vertex data only.
    #[serde(flatten)]
    pub surface: Option<SurfaceInfo>,
    /// The per-vertex arrays (GIFTI).
    pub overlays: Vec<OverlayInfo>,
}

/// A surface's counts and extent.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SurfaceInfo {
    /// Vertices.
    pub vertices: usize,
    /// Triangles.
    pub triangles: usize,
    /// Whether the file gives normals.
    pub normals: bool,
    /// Whether the file gives per-vertex scalars.
    pub scalars: bool,
    /// The per-vertex scalars' range over their finite values (text form only).
    #[serde(skip)]
    pub scalar_range: Option<(f32, f32)>,
    /// Bounding box of the vertices, mm.
    pub bounds_mm: Option<Bounds>,
    /// The space the positions are in, where the file says.
    pub coordinate_system: Option<String>,
    /// What the reader said.
    pub notes: Vec<String>,
}

/// A bounding box.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Bounds {
    /// Smallest coordinates.
    pub min: [f32; 3],
    /// Largest coordinates.
    pub max: [f32; 3],
}

/// A per-vertex array of a GIFTI file.
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(untagged)]
pub enum OverlayInfo {
    /// Scalars (sulcal depth, thickness, a statistic).
    Scalars {
        /// The array's name.
        name: String,
        /// Its intent.
        intent: String,
        /// How many values.
        values: usize,
        /// Their finite range.
        range: Option<[f32; 2]>,
    },
    /// Label keys with their table.
    Labels {
        /// The array's name.
        name: String,
        /// Its intent.
        intent: String,
        /// How many values.
        values: usize,
        /// Distinct keys in use.
        labels_used: usize,
        /// The table: key, name, RGBA.
        label_table: Vec<crate::Label>,
    },
}

impl FileInfo {
    /// The facts of a volume read from `path` (with `listing` for a DICOM directory).
    pub fn volume(path: &Path, f: &VolumeFile, listing: Option<&Listing>) -> FileInfo {
        let v = &f.volume;
        let (lo, hi) = v.range();
        let finite = |x: f64| x.is_finite().then_some(x);
        FileInfo::Volume(Box::new(VolumeInfo {
            file: path.display().to_string(),
            kind: "volume",
            format: f.format.name(),
            dims: v.dims,
            voxels: v.len(),
            spacing_mm: v.spacing,
            sample_type: v.samples.type_name(),
            slope: v.slope,
            intercept: v.intercept,
            range: [finite(lo), finite(hi)],
            range_found: [lo, hi],
            units: v.units.clone(),
            colour: v.is_colour(),
            affine_voxel_to_ras_mm: v.affine,
            notes: f.notes.clone(),
            series: listing.map(|l| l.series.iter().map(series_info).collect()),
            skipped: listing.map(|l| l.skipped.iter().map(skipped_info).collect()),
        }))
    }

    /// The facts of a surface (`None`: a GIFTI file of per-vertex data only) and its
    /// per-vertex arrays, read from `path`.
    pub fn mesh(path: &Path, f: Option<&MeshFile>, overlays: &[VertexData]) -> FileInfo {
        FileInfo::Mesh(MeshInfo {
            file: path.display().to_string(),
            kind: if f.is_some() { "mesh" } else { "vertex data" },
            format: f.map_or("GIFTI", |f| f.format.name()),
            surface: f.map(surface_info),
            overlays: overlays.iter().map(overlay_info).collect(),
        })
    }

    /// The JSON object of `glint info --json` (numbers as JSON numbers of `f64`).
    pub fn to_json(&self) -> Value {
        serde_json::to_value(self).expect("file facts always serialise")
    }
}

fn series_info(s: &crate::dicom::Series) -> SeriesInfo {
    SeriesInfo {
        uid: s.uid.clone(),
        modality: s.modality.clone(),
        description: s.description.clone(),
        files: s.files,
        slices: s.slices,
        dims: [s.columns, s.rows, s.slices],
        photometric: s.photometric.clone(),
    }
}

fn skipped_info(k: &crate::dicom::Skipped) -> SkippedInfo {
    SkippedInfo {
        file: k.path.display().to_string(),
        reason: k.reason.clone(),
        class: k.class.clone(),
        modality: k.modality.clone(),
        series: k.series.clone(),
    }
}

fn surface_info(f: &MeshFile) -> SurfaceInfo {
    let m = &f.mesh;
    let scalar_range = m.scalars.as_ref().map(|s| {
        s.iter()
            .filter(|x| x.is_finite())
            .fold((f32::INFINITY, f32::NEG_INFINITY), |(a, b), &x| {
                (a.min(x), b.max(x))
            })
    });
    SurfaceInfo {
        vertices: m.positions.len(),
        triangles: m.triangles.len(),
        normals: m.normals.is_some(),
        scalars: m.scalars.is_some(),
        scalar_range,
        bounds_mm: m.bounds().map(|(min, max)| Bounds { min, max }),
        coordinate_system: f.coordinate_system.clone(),
        notes: f.notes.clone(),
    }
}

/// The finite range of some values, `None` if there are none.
fn finite_range(v: &[f32]) -> Option<[f32; 2]> {
    v.iter()
        .filter(|x| x.is_finite())
        .fold(None, |r, &x| match r {
            None => Some([x, x]),
            Some([a, b]) => Some([a.min(x), b.max(x)]),
        })
}

fn overlay_info(o: &VertexData) -> OverlayInfo {
    let (name, intent) = (o.name.clone(), o.intent.clone());
    match &o.values {
        VertexValues::Scalars(v) => OverlayInfo::Scalars {
            name,
            intent,
            values: v.len(),
            range: finite_range(v),
        },
        VertexValues::Labels { keys, table } => OverlayInfo::Labels {
            name,
            intent,
            values: keys.len(),
            labels_used: keys.iter().collect::<std::collections::BTreeSet<_>>().len(),
            label_table: table.clone(),
        },
    }
}

impl Display for FileInfo {
    fn fmt(&self, out: &mut Formatter<'_>) -> fmt::Result {
        match self {
            FileInfo::Volume(v) => v.fmt(out),
            FileInfo::Mesh(m) => m.fmt(out),
        }
    }
}

impl Display for VolumeInfo {
    fn fmt(&self, out: &mut Formatter<'_>) -> fmt::Result {
        let [nx, ny, nz] = self.dims;
        let [sx, sy, sz] = self.spacing_mm.map(num);
        writeln!(out, "file:     {}", self.file)?;
        writeln!(out, "format:   {} volume", self.format)?;
        writeln!(out, "dims:     {nx} x {ny} x {nz} ({} voxels)", self.voxels)?;
        writeln!(out, "spacing:  {sx} x {sy} x {sz} mm")?;
        writeln!(out, "type:     {}", self.sample_type)?;
        if self.colour {
            writeln!(
                out,
                "colour:   RGB (the range below is of the grey samples)"
            )?;
        }
        if self.slope != 1.0 || self.intercept != 0.0 {
            let (m, c) = (num(self.slope), num(self.intercept));
            writeln!(out, "scaling:  value = {m} * stored + {c}")?;
        }
        let units = self
            .units
            .as_deref()
            .map(|u| format!(" {u}"))
            .unwrap_or_default();
        let [lo, hi] = self.range_found.map(num);
        writeln!(out, "range:    {lo} .. {hi}{units}")?;
        writeln!(out, "affine (voxel -> RAS+ mm):")?;
        for row in &self.affine_voxel_to_ras_mm {
            let [a, b, c, d] = row.map(num);
            writeln!(out, "  {a:>12} {b:>12} {c:>12} {d:>12}")?;
        }
        for n in &self.notes {
            writeln!(out, "note:     {n}")?;
        }
        for s in self.series.iter().flatten() {
            let m = s.modality.as_deref().unwrap_or("?");
            let d = s
                .description
                .as_deref()
                .map(|d| format!(" '{d}'"))
                .unwrap_or_default();
            let [c, r, n] = s.dims;
            writeln!(
                out,
                "series:   {} {m}{d}: {c} x {r} x {n} ({} files)",
                s.uid, s.files
            )?;
        }
        for k in self.skipped.iter().flatten() {
            writeln!(out, "skipped:  {}: {}", k.file, k.reason)?;
        }
        Ok(())
    }
}

impl Display for MeshInfo {
    fn fmt(&self, out: &mut Formatter<'_>) -> fmt::Result {
        writeln!(out, "file:      {}", self.file)?;
        match &self.surface {
            Some(s) => {
                writeln!(out, "format:    {} surface", self.format)?;
                s.fmt(out)?;
            }
            None => writeln!(out, "format:    GIFTI per-vertex data (no surface)")?,
        }
        for o in &self.overlays {
            writeln!(out, "overlay:   {o}")?;
        }
        Ok(())
    }
}

impl Display for SurfaceInfo {
    fn fmt(&self, out: &mut Formatter<'_>) -> fmt::Result {
        writeln!(out, "vertices:  {}", self.vertices)?;
        writeln!(out, "triangles: {}", self.triangles)?;
        writeln!(
            out,
            "normals:   {}",
            if self.normals { "yes" } else { "no" }
        )?;
        if let Some((lo, hi)) = self.scalar_range {
            writeln!(out, "scalars:   {} .. {}", num(lo.into()), num(hi.into()))?;
        }
        if let Some(b) = self.bounds_mm {
            let p = |p: [f32; 3]| {
                let [x, y, z] = p.map(|c| num(c.into()));
                format!("({x}, {y}, {z})")
            };
            writeln!(out, "bounds:    {} .. {} mm", p(b.min), p(b.max))?;
        }
        if let Some(cs) = &self.coordinate_system {
            writeln!(out, "space:     {cs}")?;
        }
        for n in &self.notes {
            writeln!(out, "note:      {n}")?;
        }
        Ok(())
    }
}

/// One line about a per-vertex array: name, intent, count and range or labels.
impl Display for OverlayInfo {
    fn fmt(&self, out: &mut Formatter<'_>) -> fmt::Result {
        match self {
            OverlayInfo::Scalars {
                name,
                intent,
                values,
                range,
            } => {
                let range = range
                    .map(|[lo, hi]| format!(", {} .. {}", num(lo.into()), num(hi.into())))
                    .unwrap_or_default();
                write!(out, "{name} ({intent}): {values} values{range}")
            }
            OverlayInfo::Labels {
                name,
                intent,
                values,
                labels_used,
                label_table,
            } => write!(
                out,
                "{name} ({intent}): {values} values, {labels_used} labels used of {} in the table",
                label_table.len()
            ),
        }
    }
}

/// A number with at most 4 decimals and no trailing zeros (four significant digits
/// for one too small for four decimals).
pub fn num(x: f64) -> String {
    if !x.is_finite() {
        return format!("{x}");
    }
    if x != 0.0 && x.abs() < 5e-5 {
        let s = format!("{x:.3e}");
        let (mantissa, exp) = s.split_once('e').unwrap_or((&s, "0"));
        let mantissa = mantissa.trim_end_matches('0').trim_end_matches('.');
        return format!("{mantissa}e{exp}");
    }
    let s = format!("{x:.4}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if s == "-0" {
        "0".into()
    } else {
        s.into()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dicom::{Series, Skipped};
    use crate::{Format, Samples, Volume};

    #[test]
    fn numbers_drop_trailing_zeros() {
        assert_eq!(num(1.0), "1");
        assert_eq!(num(-98.0), "-98");
        assert_eq!(num(0.5), "0.5");
        assert_eq!(num(-0.0), "0");
        assert_eq!(num(1.23456), "1.2346");
        // Tiny values keep their significant digits instead of "0".
        assert_eq!(num(1e-300), "1e-300");
        assert_eq!(num(-2.5e-6), "-2.5e-6");
        assert_eq!(num(1.23456e-5), "1.235e-5");
    }

    /// A DICOM directory's listing: one line per series and per skipped object after
    /// the volume's lines, and the same in JSON.
    #[test]
    fn dicom_listing_lines_and_json() {
        let l = Listing {
            series: vec![Series {
                uid: "1.2.3".into(),
                modality: Some("CT".into()),
                description: Some("chest".into()),
                files: 64,
                slices: 64,
                columns: 512,
                rows: 512,
                photometric: "MONOCHROME2".into(),
            }],
            skipped: vec![Skipped {
                path: "x/rs.dcm".into(),
                reason: "no PixelData: not an image (RT Structure Set Storage)".into(),
                class: Some("RT Structure Set Storage".into()),
                modality: Some("RTSTRUCT".into()),
                series: Some("1.2.4".into()),
            }],
        };
        let volume =
            Volume::new([2, 1, 1], [0.5, 1.0, 1.0], Samples::F32(vec![-1.0, 3.25])).unwrap();
        let file = VolumeFile {
            volume,
            format: Format::Dicom,
            notes: vec!["from a test".into()],
            inflate: None,
        };
        let info = FileInfo::volume(Path::new("x"), &file, Some(&l));
        let text = info.to_string();
        assert!(
            text.starts_with("file:     x\nformat:   DICOM volume\n"),
            "{text}"
        );
        assert!(text.contains("range:    -1 .. 3.25\n"), "{text}");
        assert!(
            text.ends_with(
                "note:     from a test\n\
                 series:   1.2.3 CT 'chest': 512 x 512 x 64 (64 files)\n\
                 skipped:  x/rs.dcm: no PixelData: not an image (RT Structure Set Storage)\n"
            ),
            "{text}"
        );
        let v = info.to_json();
        assert_eq!(v["kind"], "volume");
        assert_eq!(v["range"], serde_json::json!([-1.0, 3.25]));
        assert_eq!(v["series"][0]["dims"], serde_json::json!([512, 512, 64]));
        assert_eq!(v["skipped"][0]["class"], "RT Structure Set Storage");
        // Without a listing, neither key.
        let v = FileInfo::volume(Path::new("x"), &file, None).to_json();
        assert!(v.get("series").is_none() && v.get("skipped").is_none());
    }

    #[test]
    fn per_vertex_data_has_no_surface_keys() {
        let overlays = [VertexData {
            name: "sulc".into(),
            intent: "NIFTI_INTENT_SHAPE".into(),
            values: VertexValues::Scalars(vec![0.5, f32::NAN, -2.0]),
        }];
        let info = FileInfo::mesh(Path::new("s.gii"), None, &overlays);
        let v = info.to_json();
        let keys: Vec<&str> = v.as_object().unwrap().keys().map(String::as_str).collect();
        assert_eq!(keys.len(), 4, "{keys:?}");
        assert_eq!(v["kind"], "vertex data");
        assert_eq!(v["overlays"][0]["range"], serde_json::json!([-2.0, 0.5]));
        assert_eq!(
            info.to_string(),
            "file:      s.gii\nformat:    GIFTI per-vertex data (no surface)\n\
             overlay:   sulc (NIFTI_INTENT_SHAPE): 3 values, -2 .. 0.5\n"
        );
    }
}

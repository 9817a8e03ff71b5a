//! The meshes of a [`Scene`](crate::Scene): what a scene names ([`MeshSpec`],
//! [`Overlay`]), reading them with their overlays, and the defaults a surface render
//! chooses.

use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};

use glint_io::{read_mesh, read_surface_data, Format, IoError, Mesh, VertexValues};
use serde::{Deserialize, Serialize};

use glint_core::{srgb_to_linear, Clip, ColorMap, Legend, Material, RenderError, ScalarColors};
use glint_raster::{Surfaces, SURFACE_COLOR};
use glint_volume::LabelVolume;

use crate::labels::{LabelLookup, LabelMeshes, LabelSpec};

/// Supersampling factor of surface renders when the scene gives none: 2x2 samples a
/// pixel removes most stair-stepping at a quarter of 4x4's cost.
pub const DEFAULT_SSAA: u32 = 2;

/// Shininess n of surfaces when the scene gives none. glint's choice, not a standard:
/// narrow enough that the highlight shows the lobe evaluated per pixel on a cortical
/// surface, broad enough to be seen at 512x512 (VTK's own default, 1, is for
/// unlit-looking surfaces; 3D Slicer's models use 50 with specular 0).
pub const SURFACE_SHININESS: f64 = 40.0;

/// Material of surfaces when the scene gives none: the volume default's ambient 0.1
/// (VTK's, see [`Material::default`]), diffuse 0.7 and specular 0.4 so the highlight
/// is visible on light surfaces without clipping (0.1 + 0.7 + 0.4 = 1.2 at the peak
/// only where a highlight meets a surface facing the light). glint's choice.
pub const SURFACE_MATERIAL: Material = Material {
    ambient: 0.1,
    diffuse: 0.7,
    specular: 0.4,
    shade: true,
};

/// A surface mesh of a scene.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MeshSpec {
    /// The mesh file (GIFTI with POINTSET and TRIANGLE arrays, STL, OBJ, PLY).
    pub path: PathBuf,
    /// Per-vertex values shown through a colour map.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub overlay: Option<Overlay>,
    /// Colour where no overlay colours the surface, linear RGB (default:
    /// [`SURFACE_COLOR`](crate::SURFACE_COLOR)).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub color: Option<[f32; 3]>,
}

impl MeshSpec {
    /// A mesh without an overlay, in the default colour.
    pub fn new(path: impl Into<PathBuf>) -> MeshSpec {
        MeshSpec {
            path: path.into(),
            overlay: None,
            color: None,
        }
    }
}

/// Per-vertex values of a mesh: a GIFTI shape or label array, or a PLY file's vertex
/// scalar property.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Overlay {
    /// The file: GIFTI (`.gii`, e.g. FreeSurfer's sulc or curv converted, or a label
    /// parcellation) or PLY (its vertex scalar, see `glint_io::mesh::read_ply`).
    pub path: PathBuf,
    /// Which per-vertex array of a GIFTI file (`glint_io::read_surface_data`'s
    /// order); PLY files have one (default: 0).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub array: Option<usize>,
    /// The colour map of scalar overlays (default: viridis). Every scalar overlay of a
    /// scene shares one map and range (one colour bar).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub colormap: Option<ColorMap>,
    /// The values at the map's ends (default: the 2nd and 98th percentiles of all
    /// scalar overlays, [`ScalarColors::robust_range`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub range: Option<[f32; 2]>,
}

impl Overlay {
    /// The first array of `path`, every other choice left to the scene's resolution.
    pub fn new(path: impl Into<PathBuf>) -> Overlay {
        Overlay {
            path: path.into(),
            array: None,
            colormap: None,
            range: None,
        }
    }
}

/// What an overlay turned out to hold.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum OverlayKind {
    /// No overlay.
    None,
    /// Scalars, through the scene's colour map.
    Scalars,
    /// Label keys, coloured by the file's label table.
    Labels,
}

/// What the cached meshes were read from: the files, overlay files and arrays, and the
/// iso value of the volume's isosurface (as bits, so NaN-free equality is exact).
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct MeshKey {
    files: Vec<(PathBuf, Option<(PathBuf, usize)>)>,
    iso: Option<u32>,
    labels: Option<LabelSpec>,
}

impl MeshKey {
    pub(crate) fn new(specs: &[MeshSpec], iso: Option<f32>, labels: Option<&LabelSpec>) -> MeshKey {
        MeshKey {
            files: specs
                .iter()
                .map(|s| {
                    let overlay = s
                        .overlay
                        .as_ref()
                        .map(|o| (o.path.clone(), o.array.unwrap_or(0)));
                    (s.path.clone(), overlay)
                })
                .collect(),
            iso: iso.map(f32::to_bits),
            labels: labels.cloned(),
        }
    }
}

/// The meshes of a scene, read and gathered for the rasterizer.
#[derive(Clone, Debug)]
pub(crate) struct MeshSet {
    /// The surfaces; `None` when there are none (a label map drawn as a volume only).
    pub(crate) surfaces: Option<Arc<Surfaces>>,
    /// Per scene mesh (the isosurface, when there is one, comes after them and has no
    /// overlay; then the label surfaces).
    pub(crate) overlays: Vec<OverlayKind>,
    /// The colours of the meshes after the scene's (the isosurface's, then the label
    /// surfaces'), when there are label surfaces; empty otherwise (the isosurface takes
    /// the default colour).
    pub(crate) extra_colors: Vec<[f32; 3]>,
    /// The legend of the label surfaces.
    pub(crate) legend: Option<Legend>,
    /// The label map as a label volume, when the scene draws it so.
    pub(crate) label_volume: Option<Arc<LabelVolume>>,
    /// What each mesh of `surfaces` is, in their order (what a pick names).
    pub(crate) kinds: Vec<MeshKind>,
    /// The label map's voxels and names, when the scene has one (picks).
    pub(crate) labels: Option<Arc<LabelLookup>>,
    /// The surfaces last cut ([`MeshSet::surfaces_for`]): the clip, whether capped,
    /// and the cut surfaces, so that frames with the same clip cut once (and the
    /// meshes' occupancy of the light volumes, kept while the surfaces are the same,
    /// is reused).
    clipped: Arc<Mutex<Option<Clipped>>>,
}

/// Surfaces cut by a clip ([`MeshSet::surfaces_for`]).
#[derive(Debug)]
struct Clipped {
    clip: Clip,
    caps: bool,
    surfaces: Arc<Surfaces>,
}

/// What a mesh of a [`MeshSet`] is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum MeshKind {
    /// The scene's mesh `k` ([`Scene::meshes`](crate::Scene::meshes)).
    Scene(usize),
    /// The volume's isosurface (surface mode).
    Isosurface,
    /// The surface of the label with this value.
    Label(u32),
}

impl MeshSet {
    /// Reads `specs` with their overlays, and appends `extra` (the volume's isosurface)
    /// and the label surfaces.
    pub(crate) fn load(
        specs: &[MeshSpec],
        extra: Option<Mesh>,
        label_meshes: Option<LabelMeshes>,
    ) -> Result<MeshSet, RenderError> {
        let mut meshes = Vec::with_capacity(specs.len() + 1);
        let mut labels = Vec::new();
        let mut overlays = Vec::new();
        for (k, spec) in specs.iter().enumerate() {
            let mut mesh = read_mesh(&spec.path)?;
            // Only an overlay colours a surface: scalars inside the mesh file are
            // shown when the scene names the file as the overlay too.
            mesh.scalars = None;
            let kind = match &spec.overlay {
                None => OverlayKind::None,
                Some(o) => match read_overlay(o, &spec.path, mesh.positions.len())? {
                    Values::Scalars(v) => {
                        mesh.scalars = Some(v);
                        OverlayKind::Scalars
                    }
                    Values::Colors(c) => {
                        labels.push((k, c));
                        OverlayKind::Labels
                    }
                },
            };
            overlays.push(kind);
            meshes.push(mesh);
        }
        let mut extra_colors = Vec::new();
        let mut legend = None;
        let mut label_volume = None;
        let mut kinds: Vec<MeshKind> = (0..specs.len()).map(MeshKind::Scene).collect();
        if extra.is_some() {
            kinds.push(MeshKind::Isosurface);
        }
        let mut lookup = None;
        if let Some(l) = label_meshes {
            kinds.extend(l.values.iter().map(|&v| MeshKind::Label(v)));
            lookup = Some(l.lookup);
            label_volume = l.volume;
            if extra.is_some() {
                extra_colors.push(SURFACE_COLOR);
            }
            extra_colors.extend(l.colors);
            meshes.extend(extra);
            meshes.extend(l.meshes);
            legend = l.legend;
        } else {
            meshes.extend(extra);
        }
        let surfaces = if meshes.is_empty() && label_volume.is_some() {
            None
        } else {
            let mut surfaces = Surfaces::new(&meshes)?;
            for (k, colors) in labels {
                surfaces.set_vertex_colors(k, &colors)?;
            }
            Some(Arc::new(surfaces))
        };
        Ok(MeshSet {
            surfaces,
            overlays,
            extra_colors,
            legend,
            label_volume,
            kinds,
            labels: lookup,
            clipped: Arc::default(),
        })
    }

    /// The surfaces as `clip` cuts them, the cut closed with caps when `caps`
    /// ([`Surfaces::clipped`]): the uncut surfaces when nothing is cut, the last cut
    /// when the clip is the same.
    pub(crate) fn surfaces_for(
        &self,
        clip: &Clip,
        caps: bool,
    ) -> Result<Option<Arc<Surfaces>>, RenderError> {
        let Some(whole) = &self.surfaces else {
            return Ok(None);
        };
        if clip.is_empty() {
            return Ok(Some(whole.clone()));
        }
        // A poisoned lock only means another thread panicked while cutting: cut again.
        let mut last = self.clipped.lock().unwrap_or_else(|e| e.into_inner());
        if let Some(c) = last.as_ref().filter(|c| c.clip == *clip && c.caps == caps) {
            return Ok(Some(c.surfaces.clone()));
        }
        let surfaces = Arc::new(whole.clipped(clip, caps)?);
        *last = Some(Clipped {
            clip: clip.clone(),
            caps,
            surfaces: surfaces.clone(),
        });
        Ok(Some(surfaces))
    }

    /// The colours of the scalar overlays of `specs` (whose `colormap` and `range`
    /// this fills in), `None` when no overlay holds scalars. Label overlays take no
    /// map or range.
    pub(crate) fn resolve_overlays(
        &self,
        specs: &mut [MeshSpec],
    ) -> Result<Option<ScalarColors>, RenderError> {
        let mut map = None;
        let mut range = None;
        for (spec, kind) in specs.iter_mut().zip(&self.overlays) {
            let Some(o) = &mut spec.overlay else { continue };
            o.array.get_or_insert(0);
            if *kind == OverlayKind::Labels {
                if o.colormap.is_some() || o.range.is_some() {
                    return Err(RenderError::Parameter(format!(
                        "overlay {}: a label array is coloured by its label table; a colour map or range does not apply",
                        o.path.display()
                    )));
                }
                continue;
            }
            map = agree(map, o.colormap, "colour map", &o.path)?;
            range = agree(range, o.range, "range", &o.path)?;
        }
        if !self.overlays.contains(&OverlayKind::Scalars) {
            return Ok(None);
        }
        let map = map.unwrap_or_default();
        let range = match range {
            Some(r) => r,
            None => {
                let values = self
                    .surfaces
                    .as_ref()
                    .and_then(|s| s.scalars())
                    .unwrap_or_default();
                let (lo, hi) = ScalarColors::robust_range(map, values).ok_or_else(|| {
                    RenderError::Parameter(
                        "the overlays hold no finite values, or all the same value: give a range"
                            .into(),
                    )
                })?;
                [lo, hi]
            }
        };
        for (spec, kind) in specs.iter_mut().zip(&self.overlays) {
            if let (Some(o), OverlayKind::Scalars) = (&mut spec.overlay, kind) {
                o.colormap = Some(map);
                o.range = Some(range);
            }
        }
        ScalarColors::new(map, (range[0], range[1])).map(Some)
    }
}

/// The one value of a setting the overlays share: `seen` so far and `next`, which must
/// agree when both are given.
fn agree<T: PartialEq + std::fmt::Debug>(
    seen: Option<T>,
    next: Option<T>,
    what: &str,
    path: &Path,
) -> Result<Option<T>, RenderError> {
    match (seen, next) {
        (Some(a), Some(b)) if a != b => Err(RenderError::Parameter(format!(
            "overlay {}: {what} {b:?} differs from another overlay's {a:?}; the overlays share one colour bar",
            path.display()
        ))),
        (a, b) => Ok(a.or(b)),
    }
}

/// An overlay's per-vertex values.
enum Values {
    Scalars(Vec<f32>),
    /// Linear RGB per vertex; NaN where a key has no label.
    Colors(Vec<[f32; 3]>),
}

/// Reads `overlay` for the mesh at `mesh` with `vertices` vertices.
fn read_overlay(overlay: &Overlay, mesh: &Path, vertices: usize) -> Result<Values, RenderError> {
    let path = &overlay.path;
    let array = overlay.array.unwrap_or(0);
    let bad = |what: String| {
        RenderError::Mesh(IoError::Inconsistent(format!(
            "overlay {}: {what}",
            path.display()
        )))
    };
    let values = match Format::guess(path) {
        Some(Format::Gifti) => {
            let mut arrays = read_surface_data(path)?;
            if array >= arrays.len() {
                return Err(bad(format!(
                    "array {array} does not exist ({} per-vertex arrays)",
                    arrays.len()
                )));
            }
            match arrays.swap_remove(array).values {
                VertexValues::Scalars(v) => Values::Scalars(v),
                VertexValues::Labels { keys, table } => {
                    let color = |key: i32| {
                        table
                            .iter()
                            .find(|l| l.key == key)
                            .map_or([f32::NAN; 3], |l| {
                                [0, 1, 2].map(|i| srgb_to_linear(f64::from(l.rgba[i])) as f32)
                            })
                    };
                    Values::Colors(keys.into_iter().map(color).collect())
                }
            }
        }
        Some(Format::Ply) => {
            if array != 0 {
                return Err(bad(format!("array {array}: a PLY file has one (0)")));
            }
            let scalars = read_mesh(path)?.scalars.ok_or_else(|| {
                bad(
                    "no vertex scalar property (scalar, value, quality, intensity, confidence)"
                        .into(),
                )
            })?;
            Values::Scalars(scalars)
        }
        _ => return Err(bad("expected a GIFTI (.gii) or PLY (.ply) file".into())),
    };
    let n = match &values {
        Values::Scalars(v) => v.len(),
        Values::Colors(c) => c.len(),
    };
    if n != vertices {
        return Err(bad(format!(
            "{n} values for the {vertices} vertices of {}",
            mesh.display()
        )));
    }
    Ok(values)
}

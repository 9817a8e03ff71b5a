//! Picking: the 3D point a pixel of a scene's image shows ([`Renderer::pick`]), with
//! its voxel, value and label, traced as the frame traces that pixel's ray.

use std::path::PathBuf;

use glint_core::camera::Camera;
use glint_core::{RenderError, Vec3};
use glint_volume::{Field, PICK_OPACITY};
use serde::{Deserialize, Serialize};

use crate::labels::{nearest, PickLabel};
use crate::meshes::{MeshKind, MeshSet};
use crate::renderer::Renderer;
use crate::scene::{Plan, Scene};

/// What a pick hit.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum PickedObject {
    /// The ray-cast volume (composite: where the accumulated opacity reached the
    /// threshold; iso: the iso surface; MIP: the ray's maximum).
    Volume,
    /// A mesh of the scene.
    Mesh {
        /// Its position in [`Scene::meshes`].
        index: usize,
        /// Its file.
        path: PathBuf,
    },
    /// The volume's isosurface (surface mode).
    Isosurface,
    /// The surface of a label of the scene's label map.
    LabelSurface {
        /// The label's value.
        label: u32,
    },
    /// The scene's label map drawn as a label volume (its first drawn sample).
    LabelVolume,
}

/// The point a pixel of a scene's image shows ([`Renderer::pick`]).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Pick {
    /// The image point picked, pixels from the image's left edge.
    pub x: f64,
    /// The image point picked, pixels from the image's top edge.
    pub y: f64,
    /// What was hit.
    pub object: PickedObject,
    /// The point, world mm (RAS+).
    pub world_mm: [f64; 3],
    /// Its distance along the ray, mm: from the eye (perspective) or from the image
    /// plane (orthographic).
    pub depth_mm: f64,
    /// The point in the volume's voxel index space (continuous; `None` without a
    /// volume).
    pub voxel: Option<[f64; 3]>,
    /// The voxel nearest the point (`None` off the volume's grid).
    pub voxel_nearest: Option<[usize; 3]>,
    /// The stored value of that voxel in the volume's units (after the file's
    /// rescale: Hounsfield units for CT), as a radiology viewer shows it.
    pub value: Option<f64>,
    /// The value the renderer classified at the point: the reconstruction
    /// (prefiltered, trilinear) value, same units.
    pub interpolated: Option<f64>,
    /// The volume's units, when the file names them (e.g. `HU`).
    pub units: Option<String>,
    /// The label at the point (`None` without a label map, off its grid, or in its
    /// background, label 0).
    pub label: Option<PickLabel>,
    /// The ray's accumulated opacity at a volume hit (composite: the threshold; iso:
    /// 1; MIP: the maximum's classified opacity); `None` for surfaces.
    pub opacity: Option<f64>,
}

impl Pick {
    /// The distance in mm between two picked points (a ruler).
    pub fn distance_mm(&self, other: &Pick) -> f64 {
        (0..3)
            .map(|a| (self.world_mm[a] - other.world_mm[a]).powi(2))
            .sum::<f64>()
            .sqrt()
    }
}

/// Where world point `p` (mm) lies on the image of `scene`, a scene resolved by a
/// render (its [`Scene::derived`] camera, its size and projection): pixels from the
/// image's top-left corner, as [`Renderer::pick`] takes them (the point a pick
/// returns projects back to where it was picked). `None` without a derived camera,
/// or for a point at or behind a perspective camera's eye.
pub fn image_point(scene: &Scene, p: [f64; 3]) -> Option<[f64; 2]> {
    let d = scene.derived.as_ref()?;
    let v3 = |a: [f32; 3]| Vec3::new(a[0], a[1], a[2]);
    let eye = v3(d.eye);
    let forward = (v3(d.focal_point) - eye).normalize_or_zero();
    let up = v3(d.view_up);
    let right = forward.cross(up);
    let r = Vec3::new(p[0] as f32, p[1] as f32, p[2] as f32) - eye;
    let (mut u, mut v) = (f64::from(r.dot(right)), f64::from(r.dot(up)));
    if scene.camera.projection == glint_core::camera::Projection::Perspective {
        let z = f64::from(r.dot(forward));
        if z.is_nan() || z <= 1e-6 {
            return None;
        }
        (u, v) = (u / z, v / z);
    }
    let [w, h] = scene.size.map(f64::from);
    let hh = f64::from(d.parallel_scale);
    let x = (u / (hh * w / h) + 1.0) * w / 2.0;
    let y = (1.0 - v / hh) * h / 2.0;
    (x.is_finite() && y.is_finite()).then_some([x, y])
}

/// Where the ray of one pixel stops, before the volume is looked at.
struct Hit {
    object: PickedObject,
    depth: f32,
    world: [f64; 3],
    opacity: Option<f32>,
}

impl Renderer {
    /// The point image point `(x, y)` of `scene`'s image shows ([`Renderer::pick_with`]
    /// at the default opacity threshold, [`PICK_OPACITY`]).
    pub fn pick(&mut self, scene: &Scene, x: f64, y: f64) -> Result<Option<Pick>, RenderError> {
        self.pick_with(scene, x, y, PICK_OPACITY)
    }

    /// The point image point `(x, y)` of `scene`'s image shows: `(x, y)` in pixels
    /// from the image's top-left corner (pixel `(i, j)` covers `[i, i + 1) x [j, j +
    /// 1)`; its centre traces the same ray as the frame's pixel). One ray is traced
    /// with the frame's camera, sampling and classification: in composite mode to the
    /// first point where the accumulated opacity reaches `opacity` (in 0..1), in iso
    /// mode to the iso surface, in MIP to the ray's maximum; meshes (and label
    /// surfaces, and a label volume's first drawn sample) are hit where they are
    /// nearer than the volume's point, as the frame hides the volume behind them.
    ///
    /// `None` when the pixel shows nothing. A point off the image is
    /// [`RenderError::OffImage`]; nothing is rendered.
    pub fn pick_with(
        &mut self,
        scene: &Scene,
        x: f64,
        y: f64,
        opacity: f32,
    ) -> Result<Option<Pick>, RenderError> {
        let resolved = self.resolve(scene)?;
        let (w, h) = match &resolved.plan {
            Plan::Volume { frame, .. } => (frame.width, frame.height),
            Plan::Surface { settings, .. } => (settings.width, settings.height),
        };
        if !(x >= 0.0 && x < f64::from(w) && y >= 0.0 && y < f64::from(h)) {
            return Err(RenderError::OffImage {
                x,
                y,
                width: w,
                height: h,
            });
        }
        // Pixel index coordinates: pixel (i, j)'s centre at (i, j).
        let (px, py) = ((x - 0.5) as f32, (y - 0.5) as f32);
        // The meshes `resolve` read for this scene (the cache may hold another
        // scene's when this one has none).
        let set = (scene.has_meshes() || scene.is_surface())
            .then(|| self.meshes.as_ref().map(|(_, s)| s.clone()))
            .flatten();
        let hit = match &resolved.plan {
            Plan::Volume {
                tf,
                classify,
                frame,
                meshes,
                ..
            } => {
                let (class, _) = self.classification(tf, classify)?;
                let camera = class.camera(frame)?;
                let (o, d) = camera.ray(px, py, w, h);
                let mut near = meshes
                    .as_ref()
                    .and_then(|m| m.surfaces.as_ref())
                    .and_then(|s| surface_hit(s.pick(o, d), set.as_deref(), scene));
                if let Some((labels, step)) = meshes.as_ref().and_then(|m| m.label_volume.as_ref())
                {
                    let end = near.as_ref().map_or(f32::INFINITY, |n| n.depth);
                    let first = labels.first_drawn(
                        &camera,
                        &resolved.shader,
                        (px, py),
                        (w, h),
                        *step,
                        (end, &frame.clip),
                    );
                    if let Some(t) = first {
                        near = Some(Hit {
                            object: PickedObject::LabelVolume,
                            depth: t,
                            world: world(o + d * t),
                            opacity: None,
                        });
                    }
                }
                let end = near.as_ref().map_or(f32::INFINITY, |n| n.depth);
                match class.pick(&resolved.shader, frame, (px, py), end, opacity)? {
                    Some(v) => Some(Hit {
                        object: PickedObject::Volume,
                        depth: v.depth,
                        world: v.world,
                        opacity: Some(v.opacity),
                    }),
                    None => near,
                }
            }
            Plan::Surface {
                surfaces, settings, ..
            } => {
                let camera: Camera = surfaces.camera(settings)?;
                let (o, d) = camera.ray(px, py, w, h);
                surface_hit(surfaces.pick(o, d), set.as_deref(), scene)
            }
        };
        Ok(hit.map(|hit| self.describe(hit, (x, y), set.as_deref())))
    }

    /// The pick of `hit` at image point `at`: its voxel and values from the field,
    /// its label from the scene's label map.
    fn describe(&self, hit: Hit, (x, y): (f64, f64), set: Option<&MeshSet>) -> Pick {
        let field: Option<&Field> = self.field().map(|f| &**f);
        let voxel = field.map(|f| f.world_to_index(hit.world));
        let voxel_nearest = field.zip(voxel).and_then(|(f, v)| nearest(v, f.dims()));
        let value = field
            .zip(voxel_nearest)
            .and_then(|(f, n)| f.sample(n))
            .filter(|v| v.is_finite())
            .map(f64::from);
        let interpolated = field.zip(voxel).and_then(|(f, v)| {
            let dims = f.dims();
            let inside = (0..3).all(|a| v[a] >= 0.0 && v[a] <= (dims[a] - 1) as f64);
            inside.then(|| f64::from(f.value(Vec3::new(v[0] as f32, v[1] as f32, v[2] as f32))))
        });
        let label = match (&hit.object, set.and_then(|s| s.labels.as_ref())) {
            // A label's surface is that label's, wherever its smoothed surface lies.
            (PickedObject::LabelSurface { label }, Some(l)) => Some(PickLabel {
                id: *label,
                name: l.name_of(*label),
            }),
            (_, Some(l)) => l.at(hit.world),
            (_, None) => None,
        };
        Pick {
            x,
            y,
            object: hit.object,
            world_mm: hit.world,
            depth_mm: f64::from(hit.depth),
            voxel,
            voxel_nearest,
            value,
            interpolated,
            units: self.units(),
            label,
            opacity: hit.opacity.map(f64::from),
        }
    }
}

/// The pick of a surface hit, named by what its mesh is in `set`.
fn surface_hit(
    hit: Option<glint_raster::SurfaceHit>,
    set: Option<&MeshSet>,
    scene: &Scene,
) -> Option<Hit> {
    let hit = hit?;
    let kind = set.and_then(|s| s.kinds.get(hit.mesh).copied());
    let object = match kind {
        Some(MeshKind::Scene(k)) => PickedObject::Mesh {
            index: k,
            path: scene
                .meshes
                .get(k)
                .map(|m| m.path.clone())
                .unwrap_or_default(),
        },
        Some(MeshKind::Isosurface) => PickedObject::Isosurface,
        Some(MeshKind::Label(v)) => PickedObject::LabelSurface { label: v },
        None => PickedObject::Mesh {
            index: hit.mesh,
            path: PathBuf::new(),
        },
    };
    Some(Hit {
        object,
        depth: hit.t,
        world: world(hit.point),
        opacity: None,
    })
}

/// A point as f64 coordinates.
fn world(p: Vec3) -> [f64; 3] {
    [p.x, p.y, p.z].map(f64::from)
}

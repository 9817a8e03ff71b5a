//! What a device back end (glint-gpu's compute shaders) needs to ray cast a
//! classification's `local` frame as the reference loop (`raycast/caster.rs`) does: the
//! field's voxels as the bricks hold them, and a frame's rays, step, lookup table and
//! lit shader in plain numbers, and the empty-space map its composite and iso rays
//! leap by as the CPU's do. The device starts each ray at the clip box's face: the
//! CPU's start bounds skip only samples of zero opacity, so they change no pixel.

use std::sync::Arc;

use rayon::prelude::*;

use glint_core::camera::{Camera, Projection};
use glint_core::{RenderError, RenderMode, Shader};

use crate::classification::{Classification, ColourVolume, PreIntegratedTables, Sampling};
use crate::field::brick::{brick_dims, BRICK, BRICK_ROW, BRICK_SLICE, BRICK_VOXELS};
use crate::field::{Field, Filter};
use crate::raycast::FrameSettings;

/// A field's reconstruction values and quantised world gradients on the whole voxel
/// grid (i fastest): exactly what its bricks hold, so trilinear interpolation of them
/// gives the CPU's samples.
#[derive(Clone, Debug)]
pub struct VoxelGrids {
    /// Samples along i, j, k.
    pub dims: [usize; 3],
    /// The values after the prefilter (NaN replaced by the minimum).
    pub values: Vec<f32>,
    /// The world gradients as stored: `[gx, gy, gz, 0]` integers times
    /// [`VoxelGrids::gradient_scale`].
    pub gradients: Vec<[i16; 4]>,
    /// World gradient (value per mm) per integer step of [`VoxelGrids::gradients`].
    pub gradient_scale: f32,
}

impl Field {
    /// The whole grid's values and gradients as the bricks hold them (built here, in
    /// parallel, without the brick cache): 12 bytes per voxel.
    pub fn voxel_grids(&self) -> VoxelGrids {
        let [nx, ny, nz] = self.dims;
        let bd = brick_dims(self.dims);
        let plane = nx * ny;
        let mut values = vec![0.0f32; plane * nz];
        let mut gradients = vec![[0i16; 4]; plane * nz];
        // Slab `s` holds planes s·BRICK .. s·BRICK + BRICK - 1: the bricks of z index s
        // (the last slab may lie past the last brick's start: it takes that brick's
        // far face).
        values
            .par_chunks_mut(plane * BRICK)
            .zip(gradients.par_chunks_mut(plane * BRICK))
            .enumerate()
            .for_each(|(s, (vs, gs))| {
                let bz = s.min(bd[2] - 1);
                let mut v = vec![0.0f32; BRICK_VOXELS];
                let mut g = vec![[0i16; 4]; BRICK_VOXELS];
                let z0 = s * BRICK;
                let z1 = (z0 + BRICK).min(nz);
                for by in 0..bd[1] {
                    for bx in 0..bd[0] {
                        self.recipe.build([bx, by, bz], &mut v, &mut g);
                        let lo = [bx * BRICK, by * BRICK, bz * BRICK];
                        // The voxels this brick owns: its own cells' lower corners, and
                        // the far face where it is the last brick along an axis.
                        let end = |a: usize, b: usize, n: usize| {
                            if b + 1 == bd[a] {
                                n
                            } else {
                                lo[a] + BRICK
                            }
                        };
                        let (x1, y1) = (end(0, bx, nx), end(1, by, ny));
                        for z in z0..z1 {
                            for y in lo[1]..y1 {
                                let src = (z - lo[2]) * BRICK_SLICE + (y - lo[1]) * BRICK_ROW;
                                let dst = (z - z0) * plane + y * nx;
                                let w = x1 - lo[0];
                                vs[dst + lo[0]..dst + x1].copy_from_slice(&v[src..src + w]);
                                gs[dst + lo[0]..dst + x1].copy_from_slice(&g[src..src + w]);
                            }
                        }
                    }
                }
            });
        VoxelGrids {
            dims: self.dims,
            values,
            gradients,
            gradient_scale: self.gradient_scale,
        }
    }
}

/// Everything a device needs to march one `local` frame of a classification as the
/// reference loop does ([`Classification::local_march`]). Vectors are `[x, y, z]`.
#[derive(Clone, Debug)]
pub struct LocalMarch {
    /// The camera the frame frames ([`Classification::camera`]).
    pub camera: Camera,
    /// The shader placed for that camera (its world lights).
    pub shader: Shader,
    /// Perspective: the eye in index units; orthographic: the image centre.
    pub origin: [f32; 3],
    /// The camera's forward, right and up axes in index units per mm.
    pub index_axes: [[f32; 3]; 3],
    /// The same axes in world units (unit vectors).
    pub world_axes: [[f32; 3]; 3],
    /// Whether the rays diverge from the eye.
    pub perspective: bool,
    /// `[u0, du, v0, dv]`: image-plane coordinates `u0 + x du`, `v0 + y dv` of pixel
    /// `(x, y)` ([`Camera::image_plane`]).
    pub image_plane: [f32; 4],
    /// The index-space box rays are clipped to (lo, hi).
    pub clip_box: ([f32; 3], [f32; 3]),
    /// The sample step in mm.
    pub dt: f32,
    /// Lookup table: entry of value `v` is `round((v - lut_lo) · lut_scale)` clamped.
    pub lut_lo: f32,
    /// See [`LocalMarch::lut_lo`].
    pub lut_scale: f32,
    /// `[r, g, b, alpha']` per entry (linear colour, opacity corrected for the step).
    pub lut: Vec<[f32; 4]>,
    /// Composite or MIP.
    pub mode: RenderMode,
    /// Background, linear RGB.
    pub background: [f32; 3],
    /// Accumulated opacity at which a composite ray stops.
    pub termination: f32,
    /// The iso mode's threshold ([`ClassifySettings::iso`](crate::ClassifySettings::iso)).
    pub iso: f32,
    /// A pre-integrated composite frame's tables (`None`: point sampling).
    pub pre: Option<PreIntegratedTables>,
    /// The frame's clip planes and crop box in index space (`None`: no clip).
    pub clip: Option<DeviceClip>,
    /// For the tricubic filter, the matrix taking the spline's index-space
    /// derivatives to the world gradient (rows); `None` for the trilinear filter.
    pub tricubic: Option<[[f32; 3]; 3]>,
    /// A colour volume whose colours replace the lookup table's (in composite and
    /// iso frames; MIP keeps the table's).
    pub colour: Option<Arc<ColourVolume>>,
    /// Macro cells ([`crate::MACRO_CELL`] voxels a side) along i, j, k.
    pub cell_dims: [usize; 3],
    /// Per macro cell (i fastest): 0 where a sample can contribute (composite) or
    /// reach the threshold (iso), else the chessboard distance in cells to the
    /// nearest such cell: the empty-space map the CPU's rays leap by (all 0 without
    /// [`ClassifySettings::skip_empty`](crate::ClassifySettings::skip_empty)).
    pub distance: Vec<u8>,
}

/// A frame's clip in index space, as the ray caster applies it (`clip.rs`): each ray
/// keeps the part where every plane's signed distance is non-negative, and a sample
/// within `depth` mm of its nearest plane with a gradient weaker than `strong` is
/// shaded with the gradient blended towards that plane's normal.
#[derive(Clone, Debug)]
pub struct DeviceClip {
    /// Per half-space `[a.x, a.y, a.z, b, n.x, n.y, n.z, 0]`: signed distance (mm)
    /// `a · p + b` of index-space point `p`, and the unit world normal into the kept
    /// side.
    pub planes: Vec<[f32; 8]>,
    /// Samples closer than this (mm) to a plane lie on its cut face.
    pub depth: f32,
    /// The gradient magnitude a cut face's normal is given.
    pub strong: f32,
}

impl Classification {
    /// The numbers of `settings`' `local` frame lit by `shader`, for a device back end
    /// (composite with point or pre-integrated sampling, MIP or iso; either filter;
    /// clip planes and crop boxes; a colour volume's colours); an error for the
    /// surface mode, which is rasterised, never ray cast.
    pub fn local_march(
        &self,
        shader: &Shader,
        settings: &FrameSettings,
    ) -> Result<LocalMarch, RenderError> {
        let unsupported = |what: &str| {
            Err(RenderError::Parameter(format!(
                "the GPU back end does not render {what} yet"
            )))
        };
        if self.settings.mode == RenderMode::Surface {
            return unsupported("surface mode");
        }
        let camera = self.camera(settings)?;
        let shader = shader.placed(&camera);
        let field = &*self.field;
        let pre = (self.settings.mode == RenderMode::Composite
            && self.settings.sampling == Sampling::PreIntegrated)
            .then(|| self.lut.pre.device_tables());
        let clip = self.index_clip(&shader, settings).map(|c| {
            let (planes, depth, strong) = c.device_planes();
            DeviceClip {
                planes,
                depth,
                strong,
            }
        });
        let tricubic =
            (field.filter() == Filter::Tricubic).then_some(field.recipe.to_world_gradient);
        let to_index = |v: glint_core::Vec3| {
            let d = field.direction_to_index([v.x as f64, v.y as f64, v.z as f64]);
            [d[0] as f32, d[1] as f32, d[2] as f32]
        };
        let e = camera.eye;
        let o = field.world_to_index([e.x as f64, e.y as f64, e.z as f64]);
        let world = [camera.forward, camera.right, camera.up];
        Ok(LocalMarch {
            origin: [o[0] as f32, o[1] as f32, o[2] as f32],
            index_axes: world.map(to_index),
            world_axes: world.map(|v| [v.x, v.y, v.z]),
            perspective: camera.projection == Projection::Perspective,
            image_plane: camera.image_plane(settings.width, settings.height),
            clip_box: (
                self.clip_box.0.map(|x| x as f32),
                self.clip_box.1.map(|x| x as f32),
            ),
            dt: (self.settings.step * field.min_spacing()) as f32,
            lut_lo: self.lut.lo,
            lut_scale: self.lut.scale,
            lut: self.lut.entries.clone(),
            mode: self.settings.mode,
            background: settings.background,
            termination: crate::raycast::TERMINATION_OPACITY,
            iso: self.settings.iso,
            pre,
            clip,
            tricubic,
            colour: self.colour.clone(),
            cell_dims: field.cell_dims,
            distance: self.distance.clone(),
            camera,
            shader,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glint_core::Vec3;

    #[test]
    fn voxel_grids_hold_the_fields_own_samples() {
        // 35 voxels: two full bricks and a last one of three (the far face's slab).
        let volume = crate::phantom::shepp_logan(35).unwrap();
        let field = Field::with_prefilter(&volume, crate::Prefilter::Binomial).unwrap();
        let grids = field.voxel_grids();
        let [nx, ny, _] = grids.dims;
        for ijk in [
            [0, 0, 0],
            [15, 16, 17],
            [34, 34, 34],
            [16, 3, 32],
            [33, 20, 1],
        ] {
            let i = ijk[0] + nx * (ijk[1] + ny * ijk[2]);
            let p = Vec3::new(ijk[0] as f32, ijk[1] as f32, ijk[2] as f32);
            assert_eq!(grids.values[i], field.value(p), "{ijk:?}");
            let g = grids.gradients[i];
            let want = field.gradient(p);
            let s = grids.gradient_scale;
            let got = Vec3::new(g[0] as f32 * s, g[1] as f32 * s, g[2] as f32 * s);
            assert!(
                (got - want).length() <= 1e-6 * (1.0 + want.length()),
                "{ijk:?}"
            );
        }
    }
}

//! The `shadows` model's light volumes as frames read them ([`ShadowField`]): per
//! light, the transmittance on a coarse grid, looked up trilinearly at each shaded
//! sample, and the ambient occlusion. The light transport (`transport`) builds them;
//! the ray caster (`raycast`) reads them.

use std::sync::Arc;

use glint_core::{RenderError, Shader, Vec3, MAX_LIGHTS};

use crate::classification::LIGHT_CELL;

/// One light's transmittance grid, stored plane by plane along its sweep axis.
pub(crate) struct LightGrid {
    /// The sweep axis, then the two others: storage is `[m][v][u]` with `m` along
    /// `axes[0]`, `v` along `axes[2]`, `u` along `axes[1]`.
    pub(crate) axes: [usize; 3],
    /// Grid extents along `axes`.
    pub(crate) len: [usize; 3],
    pub(crate) t: Vec<f32>,
    /// Added to a sample's grid position before the lookup: the shadow bias, towards
    /// the light.
    pub(crate) offset: Vec3,
}

impl LightGrid {
    /// Transmittance at grid position `g` (grid units, before the bias).
    #[inline(always)]
    fn at(&self, g: Vec3) -> f32 {
        let g = g + self.offset;
        let q = [
            g.get(self.axes[0]),
            g.get(self.axes[1]),
            g.get(self.axes[2]),
        ];
        trilinear(&self.t, self.len, q)
    }
}

/// Trilinear interpolation of `grid` (extents `len`, storage `[q0][q2][q1]`) at `q`,
/// clamped to the grid.
#[inline(always)]
fn trilinear(grid: &[f32], len: [usize; 3], q: [f32; 3]) -> f32 {
    let mut i = [0usize; 3];
    let mut f = [0.0f32; 3];
    for a in 0..3 {
        let top = (len[a] - 1) as f32;
        let x = q[a].max(0.0).min(top);
        let lo = (x as usize).min(len[a].saturating_sub(2));
        i[a] = lo;
        f[a] = if len[a] > 1 { x - lo as f32 } else { 0.0 };
    }
    let (s1, s0) = (len[1], len[1] * len[2]);
    let o1 = if len[1] > 1 { 1 } else { 0 };
    let o2 = if len[2] > 1 { s1 } else { 0 };
    let o0 = if len[0] > 1 { s0 } else { 0 };
    let base = i[0] * s0 + i[2] * s1 + i[1];
    let at = |o: usize| grid[base + o];
    let lerp = |a: f32, b: f32, t: f32| a + t * (b - a);
    let c00 = lerp(at(0), at(o1), f[1]);
    let c01 = lerp(at(o2), at(o2 + o1), f[1]);
    let c10 = lerp(at(o0), at(o0 + o1), f[1]);
    let c11 = lerp(at(o0 + o2), at(o0 + o2 + o1), f[1]);
    lerp(lerp(c00, c01, f[2]), lerp(c10, c11, f[2]), f[0])
}

/// One light's transmittance grid as a device uploads it ([`ShadowField::light_grid`]).
pub struct LightGridView<'a> {
    /// The sweep axis, then the two others.
    pub axes: [usize; 3],
    /// The grid's extents along `axes`.
    pub len: [usize; 3],
    /// The values, storage `[m][v][u]`: `m` along `axes[0]`, `v` along `axes[2]`,
    /// `u` along `axes[1]`.
    pub t: &'a [f32],
    /// Added to a sample's grid position before the lookup (the shadow bias).
    pub offset: [f32; 3],
}

/// The light volumes of one frame: each placed light's transmittance grid, and the
/// classification's ambient occlusion when asked for. Built by
/// [`Classification::shadow_field`](crate::Classification::shadow_field) for a shader
/// placed for a camera, and valid for every frame whose lights point the same way
/// (a viewer keeps it while only the lobe, the material or the size change).
pub struct ShadowField {
    /// The world directions it was built for (bit patterns), in light order.
    pub(crate) dirs: Vec<[u32; 3]>,
    pub(crate) lights: Vec<LightGrid>,
    pub(crate) occlusion: Option<(Arc<Vec<f32>>, [usize; 3])>,
}

impl ShadowField {
    /// The world directions of `shader`'s placed lights, as [`ShadowField`] keeps them.
    pub(crate) fn light_bits(shader: &Shader) -> Vec<[u32; 3]> {
        shader
            .world_lights()
            .iter()
            .map(|(l, _)| [l.x.to_bits(), l.y.to_bits(), l.z.to_bits()])
            .collect()
    }

    /// Errors unless it was built for the lights of `shader` (placed).
    pub(crate) fn check_lights(&self, shader: &Shader) -> Result<(), RenderError> {
        if ShadowField::light_bits(shader) != self.dirs {
            return Err(RenderError::Parameter(
                "the light volumes were built for other lights (or another camera)".into(),
            ));
        }
        Ok(())
    }

    /// Whether it was built for the lights of `shader` placed for `camera`.
    pub fn is_for(&self, shader: &Shader, camera: &glint_core::Camera) -> bool {
        ShadowField::light_bits(&shader.placed(camera)) == self.dirs
    }

    /// How many lights it holds.
    pub fn lights(&self) -> usize {
        self.lights.len()
    }

    /// Whether it holds ambient occlusion.
    pub fn has_occlusion(&self) -> bool {
        self.occlusion.is_some()
    }

    /// The transmittance of each light to index-space point `p` into `out` (the
    /// first [`ShadowField::lights`] entries), and the ambient occlusion there (1
    /// without it).
    #[inline(always)]
    pub(crate) fn at(&self, p: Vec3, out: &mut [f32; MAX_LIGHTS]) -> f32 {
        let g = p * (1.0 / LIGHT_CELL as f32);
        for (o, l) in out.iter_mut().zip(&self.lights) {
            *o = l.at(g);
        }
        match &self.occlusion {
            Some((ao, d)) => trilinear(ao, [d[2], d[0], d[1]], [g.z, g.x, g.y]),
            None => 1.0,
        }
    }

    /// The side of a grid cell in voxels: a sample at index-space point `p` reads the
    /// grids at `p / cell` (grid units).
    pub fn cell() -> f32 {
        LIGHT_CELL as f32
    }

    /// Light `i`'s transmittance grid as a device uploads it.
    pub fn light_grid(&self, i: usize) -> Option<LightGridView<'_>> {
        let l = self.lights.get(i)?;
        let o = l.offset;
        Some(LightGridView {
            axes: l.axes,
            len: l.len,
            t: &l.t,
            offset: [o.x, o.y, o.z],
        })
    }

    /// The ambient occlusion grid (storage `[k][j][i]`) and its dims `[ni, nj, nk]`,
    /// when it holds one.
    pub fn occlusion_grid(&self) -> Option<(&[f32], [usize; 3])> {
        self.occlusion.as_ref().map(|(o, d)| (o.as_slice(), *d))
    }

    /// The transmittance of light `i` at index-space point `p` (tests and reports).
    pub fn transmittance(&self, i: usize, p: [f32; 3]) -> Option<f32> {
        let l = self.lights.get(i)?;
        Some(l.at(Vec3::new(p[0], p[1], p[2]) * (1.0 / LIGHT_CELL as f32)))
    }
}

/// Grid planes between a sample and the point whose transmittance it reads (towards
/// the light): `transport/shadows.rs`'s `SHADOW_BIAS_PLANES`, which a device's sweep
/// mirrors.
const SWEEP_BIAS_PLANES: f32 = 1.0;

/// One light's sweep as a device runs it (`transport/shadows.rs`' `LightGrid::new`
/// set up for the light's index-space direction): the grid's axes and extents, the
/// step between planes and the shift of the upstream point, the plane order, the
/// lookup's bias.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightSweep {
    /// The sweep axis (the direction's largest component), then the two others.
    pub axes: [usize; 3],
    /// The grid's extents along `axes`.
    pub len: [usize; 3],
    /// mm along the light between two planes (the segment's length).
    pub s: f32,
    /// The upstream point's shift along `axes[1]` and `axes[2]`, grid units.
    pub shift: [f32; 2],
    /// Whether the planes run from the last to the first (the light on the high side).
    pub from_last: bool,
    /// Whether the light has a component along the sweep axis (else every
    /// transmittance is 1).
    pub swept: bool,
    /// Added to a sample's grid position before the lookup.
    pub offset: [f32; 3],
}

/// What a device needs to build a frame's light volumes itself
/// ([`Classification::light_sweeps`](crate::Classification::light_sweeps)).
pub struct LightSweeps<'a> {
    /// The averaged extinction on the grid (i fastest) and the grid's dims (shared:
    /// a device may keep a weak reference to know when it is gone).
    pub sigma: (&'a Arc<Vec<f32>>, [usize; 3]),
    /// One sweep per placed light, in light order.
    pub lights: Vec<LightSweep>,
    /// The ambient occlusion grid when asked for (storage `[k][j][i]`).
    pub occlusion: Option<Arc<Vec<f32>>>,
}

impl LightSweep {
    /// The sweep for index-space direction `d` (towards the light) on a grid of `dims`.
    fn new(d: Vec3, dims: [usize; 3]) -> LightSweep {
        let da = [d.x, d.y, d.z];
        let a = (0..3)
            .max_by(|&x, &y| da[x].abs().total_cmp(&da[y].abs()))
            .expect("three axes");
        let (b, c) = ((a + 1) % 3, (a + 2) % 3);
        let len = [dims[a], dims[b], dims[c]];
        let h = LIGHT_CELL as f32;
        if da[a] == 0.0 {
            return LightSweep {
                axes: [a, b, c],
                len,
                s: 0.0,
                shift: [0.0; 2],
                from_last: false,
                swept: false,
                offset: [0.0; 3],
            };
        }
        let s = h / da[a].abs();
        let x = s * SWEEP_BIAS_PLANES / h;
        LightSweep {
            axes: [a, b, c],
            len,
            s,
            shift: [da[b] * s / h, da[c] * s / h],
            from_last: da[a] > 0.0,
            swept: true,
            offset: [x * da[0], x * da[1], x * da[2]],
        }
    }
}

impl crate::Classification {
    /// The inputs of `frame`'s light volumes for a device that sweeps them itself, as
    /// [`Classification::shadow_field`](crate::Classification::shadow_field) would
    /// build them without occluders; `None` for a clipped frame (the clip empties
    /// grid points: such frames take the CPU's light volumes).
    pub fn light_sweeps(
        &self,
        shader: &Shader,
        frame: &crate::FrameSettings,
        settings: &crate::ShadowSettings,
    ) -> Result<Option<LightSweeps<'_>>, RenderError> {
        let camera = self.camera(frame)?;
        let placed = shader.placed(&camera);
        if self.index_clip(shader, frame).is_some() {
            return Ok(None);
        }
        if placed.world_lights().len() > MAX_LIGHTS {
            return Err(RenderError::Parameter(format!(
                "{} lights: at most {MAX_LIGHTS}",
                placed.world_lights().len()
            )));
        }
        let field = &**self.field();
        let density = self.density();
        let lights = placed
            .world_lights()
            .iter()
            .map(|&(l, _)| LightSweep::new(field.index_direction(l), density.dims))
            .collect();
        Ok(Some(LightSweeps {
            sigma: (&density.sigma, density.dims),
            lights,
            occlusion: settings.occlusion.then(|| self.occlusion()),
        }))
    }
}

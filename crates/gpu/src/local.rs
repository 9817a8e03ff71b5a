//! The `local` model on the GPU: the field as two 3D textures (values R32Float,
//! quantised gradients Rgba16Sint, exactly the bricks' data), the lookup table and
//! the frame's numbers in buffers, one compute invocation per pixel (`local.wgsl`).

use std::sync::Arc;

use glint_core::{Image, RenderError, RenderMode, RenderStats, Shader};
use glint_lobe::{Geometry, LobeKind, Specular};
use glint_volume::{
    Classification, ColourVolume, Field, FrameSettings, LocalMarch, ShadowField, ShadowSettings,
    VoxelGrids,
};
use wgpu::util::DeviceExt;

use crate::adapter::{ColourCache, FieldCache, Gpu, GpuError};

/// Pixels per workgroup side (`@workgroup_size(8, 8, 1)` in the shader).
const GROUP: u32 = 8;

/// The shader's `Params` in f32 words (`size` and `dims` as u32 bits): 21 vec4
/// fields, two vec4<u32> and 8 lights.
const PARAM_WORDS: usize = 4 * (21 + 2 + 8);

/// Bins of the lookup table and its pre-integrated tables (`BINS` in the shader).
const BINS: usize = 4096;

/// Planes of the volume uploaded per `write_texture` (bounds the staging memory).
const UPLOAD_PLANES: usize = 16;

/// The lobe as the shader's `[form, n, a, v]` (form 4: the cosine table of
/// [`spec_table`]).
fn lobe_words(specular: &Specular) -> [f32; 4] {
    let Some(lobe) = specular.lobe() else {
        return [4.0, 0.0, 0.0, 0.0];
    };
    let n = lobe.n() as f32;
    match lobe.kind() {
        LobeKind::Exact => [0.0, n, 0.0, 0.0],
        LobeKind::Schlick => [2.0, n, 0.0, 0.0],
        LobeKind::Gauss => [3.0, n, 0.0, 0.0],
        LobeKind::EnergyFit | LobeKind::SlopeFit | LobeKind::Minimax => {
            let a = lobe.coefficient().unwrap_or(0.0) as f32;
            [1.0, n, a, lobe.v() as f32]
        }
    }
}

/// The hw lobe's cosine table as the shader reads it: `[scale, first code, entries]`
/// and the values from the first code on (`CosTable::value` clamps a code below it
/// to the first entry, above the last to the last), read through the table's own
/// `value`; a one-entry placeholder for a closed-form lobe.
fn spec_table(specular: &Specular) -> Result<([f32; 3], Vec<f32>), GpuError> {
    let Specular::Table(table) = specular else {
        return Ok(([1.0, 0.0, 1.0], vec![0.0]));
    };
    let one = 1i32 << table.frac_bits();
    let codes = -one..=one;
    let first = codes.clone().map(|c| table.value(c)).next().unwrap_or(0.0);
    // The leading run of the first value is stored once (as `CosTable` stores it).
    let lo = codes
        .clone()
        .take_while(|&c| table.value(c) == first)
        .last()
        .unwrap_or(-one);
    let values: Vec<f32> = (lo..=one).map(|c| table.value(c)).collect();
    Ok(([one as f32, lo as f32, values.len() as f32], values))
}

/// The pre-integrated tables in the shader's layout (`PRE_*`): the point segments,
/// the integrals' high and low f32 halves, the slopes, then per entry the visible
/// count and the opacity table; a one-entry placeholder for point sampling.
fn pre_tables(m: &LocalMarch) -> Result<Vec<[f32; 4]>, GpuError> {
    let Some(t) = &m.pre else {
        return Ok(vec![[0.0; 4]]);
    };
    if t.point.len() != BINS
        || t.cum.len() != BINS + 1
        || t.slope.len() != BINS
        || t.visible.len() != BINS + 1
        || t.opacity.len() != BINS
    {
        return Err(GpuError::Unsupported(format!(
            "pre-integrated tables of {} bins (the shader reads {BINS})",
            t.point.len()
        )));
    }
    let hi = |x: &[f64; 4]| x.map(|v| v as f32);
    let lo = |x: &[f64; 4]| x.map(|v| (v - f64::from(v as f32)) as f32);
    let mut out = Vec::with_capacity(5 * BINS + 3);
    out.extend(&t.point);
    out.extend(t.cum.iter().map(hi));
    out.extend(t.cum.iter().map(lo));
    out.extend(t.slope.iter().map(hi));
    out.extend((0..=BINS).map(|i| {
        let opacity = t.opacity.get(i).copied().unwrap_or(0.0);
        [t.visible[i] as f32, opacity, 0.0, 0.0]
    }));
    Ok(out)
}

/// The empty-space map as the shader's `distance`: four cells a word, the first in
/// the low byte (at least one word).
fn distance_words(m: &LocalMarch) -> Vec<u32> {
    let mut words: Vec<u32> = m
        .distance
        .chunks(4)
        .map(|c| {
            c.iter()
                .enumerate()
                .fold(0u32, |w, (i, &d)| w | u32::from(d) << (8 * i))
        })
        .collect();
    if words.is_empty() {
        words.push(0);
    }
    words
}

/// The clip's half-spaces as the shader's `planes` (two entries each; one
/// placeholder entry when there is no clip).
fn clip_planes(m: &LocalMarch) -> Vec<[f32; 4]> {
    match &m.clip {
        Some(c) if !c.planes.is_empty() => c
            .planes
            .iter()
            .flat_map(|p| [[p[0], p[1], p[2], p[3]], [p[4], p[5], p[6], p[7]]])
            .collect(),
        _ => vec![[0.0; 4]],
    }
}

/// The shader's `Params` for `m` on a field of `dims` with gradient scale `scale`,
/// the hw lobe's table described by `table` ([`spec_table`]).
fn params(
    m: &LocalMarch,
    settings: &FrameSettings,
    (dims, scale): ([usize; 3], f32),
    table: [f32; 3],
) -> Vec<u32> {
    let shader: &Shader = &m.shader;
    let mut w: Vec<f32> = Vec::with_capacity(PARAM_WORDS);
    let v4 = |w: &mut Vec<f32>, a: [f32; 3], b: f32| w.extend([a[0], a[1], a[2], b]);
    v4(&mut w, m.origin, if m.perspective { 1.0 } else { 0.0 });
    for axis in m.index_axes.iter().chain(&m.world_axes) {
        v4(&mut w, *axis, 0.0);
    }
    w.extend(m.image_plane);
    v4(&mut w, m.clip_box.0, m.dt);
    v4(&mut w, m.clip_box.1, m.termination);
    w.extend([m.lut_lo, m.lut_scale, scale, m.lut.len() as f32]);
    let mode = match m.mode {
        RenderMode::Mip => 1.0,
        RenderMode::Iso => 2.0,
        _ => 0.0,
    };
    v4(&mut w, m.background, mode);
    let mat = shader.material();
    w.extend([
        mat.ambient,
        mat.diffuse,
        mat.specular,
        f32::from(u8::from(mat.shade)),
    ]);
    let lights = shader.world_lights();
    let geometry = match shader.geometry() {
        Geometry::Phong => 0.0,
        Geometry::Blinn => 1.0,
    };
    w.extend([
        shader.gate(),
        shader.surface_weight(),
        geometry,
        lights.len() as f32,
    ]);
    w.extend(lobe_words(shader.specular()));
    let (clip_count, depth, strong) = m.clip.as_ref().map_or((0.0, 0.0, 1.0), |c| {
        (c.planes.len() as f32, c.depth, c.strong)
    });
    w.extend([
        m.iso,
        f32::from(u8::from(m.pre.is_some())),
        f32::from(u8::from(m.tricubic.is_some())),
        clip_count,
    ]);
    let (m_max, m_scale) = m.pre.as_ref().map_or((0.0, 0.0), |t| (t.m_max, t.m_scale));
    w.extend([depth, strong, m_max, m_scale]);
    w.extend(table);
    w.push(f32::from(u8::from(m.colour.is_some())));
    for row in m.tricubic.unwrap_or_default() {
        v4(&mut w, row, 0.0);
    }
    let mut words: Vec<u32> = w.iter().map(|x| x.to_bits()).collect();
    let cd = m.cell_dims.map(|c| c as u32);
    words.extend([settings.width, settings.height, cd[0], cd[1]]);
    words.extend([dims[0] as u32, dims[1] as u32, dims[2] as u32, cd[2]]);
    for i in 0..8 {
        let (d, intensity) = lights
            .get(i)
            .map_or(([0.0; 3], 0.0), |(d, s)| ([d.x, d.y, d.z], *s));
        words.extend([d[0], d[1], d[2], intensity].map(f32::to_bits));
    }
    debug_assert_eq!(words.len(), PARAM_WORDS);
    words
}

/// The `shadows` model's light volumes as the shader's `shadow` (header) and
/// `light` (values): `shadow[0]` = `[on, has occlusion, anisotropy, 1 / cell]`,
/// `shadow[1]` = the occlusion grid's dims and first value's index, then per light
/// its axes and first value's index, its extents, its bias; the values of every
/// light's grid, then the occlusion's. Placeholders (off) without light volumes.
fn shadow_tables(
    shadows: Option<&ShadowField>,
    anisotropy: f32,
) -> Result<(Vec<[f32; 4]>, Vec<f32>), GpuError> {
    let Some(s) = shadows else {
        return Ok((vec![[0.0; 4]; 2], vec![1.0]));
    };
    let mut head = vec![[0.0; 4]; 2];
    let mut values: Vec<f32> = Vec::new();
    let index = |values: &Vec<f32>| -> Result<f32, GpuError> {
        // The shader reads the indices as f32: exact below 2^24.
        if values.len() >= 1 << 24 {
            return Err(GpuError::Unsupported(
                "light volumes of 2^24 values or more".into(),
            ));
        }
        Ok(values.len() as f32)
    };
    for i in 0..s.lights() {
        let g = s.light_grid(i).expect("i < lights");
        let first = index(&values)?;
        head.push([g.axes[0] as f32, g.axes[1] as f32, g.axes[2] as f32, first]);
        head.push([g.len[0] as f32, g.len[1] as f32, g.len[2] as f32, 0.0]);
        head.push([g.offset[0], g.offset[1], g.offset[2], 0.0]);
        values.extend_from_slice(g.t);
    }
    let occlusion = s.occlusion_grid();
    if let Some((o, d)) = occlusion {
        head[1] = [d[0] as f32, d[1] as f32, d[2] as f32, index(&values)?];
        values.extend_from_slice(o);
    }
    head[0] = [
        1.0,
        f32::from(u8::from(occlusion.is_some())),
        anisotropy,
        1.0 / ShadowField::cell(),
    ];
    if values.is_empty() {
        values.push(1.0);
    }
    Ok((head, values))
}

/// Where a `shadows` frame's light volumes come from.
#[derive(Clone, Copy)]
enum LightVolumes<'a> {
    /// Built on the CPU ([`Classification::shadow_field`]), uploaded.
    Built(&'a ShadowField),
    /// Swept on the GPU for these settings.
    Swept(ShadowSettings),
}

impl Gpu {
    /// The `local` frame of `class` for `settings` lit by `shader`, as
    /// [`Classification::frame`] renders it on the CPU (same rays, samples, lookup
    /// table, gradients and lighting; floating-point differences only): composite with
    /// point sampling or pre-integrated segments, MIP or iso; either filter; clip
    /// planes and crop boxes; a colour volume's colours; every lobe, the hw lobe's
    /// table included. Errors for a volume past the adapter's 3D texture limit and
    /// for device failures.
    pub fn render_local(
        &mut self,
        class: &Classification,
        shader: &Shader,
        settings: &FrameSettings,
    ) -> Result<Image, GpuError> {
        self.render(class, shader, settings, None)
    }

    /// The `shadows` frame of `class` for `settings` lit by `shader` through the
    /// light volumes `shadows` (built on the CPU by
    /// [`Classification::shadow_field`] for this shader and frame, uploaded as
    /// buffers): [`Gpu::render_local`]'s march, each shaded sample lit as the CPU's
    /// `shadows` model lights it (each light scaled by its transmittance, the medium
    /// by the phase function, the ambient term by the occlusion). Errors as
    /// [`Gpu::render_local`] does, and for light volumes built for other lights.
    pub fn render_shadows(
        &mut self,
        class: &Classification,
        shader: &Shader,
        settings: &FrameSettings,
        shadows: &ShadowField,
    ) -> Result<Image, GpuError> {
        self.render(class, shader, settings, Some(LightVolumes::Built(shadows)))
    }

    /// The `shadows` frame as [`Gpu::render_shadows`] renders it, its light volumes
    /// swept on the GPU (`sweep.wgsl`, one dispatch per grid plane of each light)
    /// from the classification's averaged extinction, the ambient occlusion (when
    /// `shadows` asks for it) the classification's own; a clipped frame's light
    /// volumes (the clip empties grid points) are built on the CPU.
    pub fn render_shadows_swept(
        &mut self,
        class: &Classification,
        shader: &Shader,
        settings: &FrameSettings,
        shadows: &ShadowSettings,
    ) -> Result<Image, GpuError> {
        self.render(class, shader, settings, Some(LightVolumes::Swept(*shadows)))
    }

    fn render(
        &mut self,
        class: &Classification,
        shader: &Shader,
        settings: &FrameSettings,
        shadows: Option<LightVolumes<'_>>,
    ) -> Result<Image, GpuError> {
        let march = class.local_march(shader, settings).map_err(|e| {
            // The caller names the parameter error once (`--device gpu: ...`).
            GpuError::Unsupported(match e {
                RenderError::Parameter(line) => line,
                e => e.to_string(),
            })
        })?;
        let (shadow_head, light_values) =
            self.shadow_inputs((class, &march), (shader, settings), shadows)?;
        let field = class.field();
        let dims = field.dims();
        let (w, h) = (settings.width, settings.height);
        let out_size = u64::from(w) * u64::from(h) * 16;
        self.need(
            "the largest storage buffer binding",
            self.limits.max_storage_buffer_binding_size,
            out_size,
        )?;
        if let Some(c) = &march.colour {
            let side = *c.dims().iter().max().expect("three dims") as u64;
            let have = u64::from(self.limits.max_texture_dimension_3d);
            self.need("the largest 3D texture side", have, side)?;
        }
        // Refused before the error scopes open (an early return leaves them open).
        crate::pages::layout(dims, self.texture_side() as usize)?;
        let scopes = self.scopes();
        self.upload(field)?;
        self.upload_colour(march.colour.as_ref());
        let paged = self.field.as_ref().is_some_and(|c| c.paged);
        let tricubic = march.tricubic.is_some();
        let pipeline = self.pipeline(tricubic, paged);
        let cache = self.field.as_ref().expect("uploaded above");
        let colours = self.colour.as_ref().expect("uploaded above");
        let (table, spec) = spec_table(march.shader.specular())?;
        let words = params(&march, settings, (dims, cache.gradient_scale), table);
        let device = &self.device;
        let uniform = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("glint params"),
            contents: bytemuck::cast_slice(&words),
            usage: wgpu::BufferUsages::UNIFORM,
        });
        let storage = |label, contents: &[u8]| {
            device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents,
                usage: wgpu::BufferUsages::STORAGE,
            })
        };
        let lut = storage("glint lut", bytemuck::cast_slice(&march.lut));
        let planes = storage("glint planes", bytemuck::cast_slice(&clip_planes(&march)));
        let pre = storage("glint pre", bytemuck::cast_slice(&pre_tables(&march)?));
        let spec = storage("glint spec", bytemuck::cast_slice(&spec));
        let linear = march.colour.as_ref().map_or([0.0; 256], |c| *c.linear());
        let linear = storage("glint srgb", bytemuck::cast_slice(&linear));
        let distance = storage(
            "glint distance",
            bytemuck::cast_slice(&distance_words(&march)),
        );
        let shadow_head = storage("glint shadow", bytemuck::cast_slice(&shadow_head));
        let out = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("glint image"),
            size: out_size,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        let bind = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("glint local"),
            layout: &pipeline.get_bind_group_layout(0),
            entries: &[
                entry(0, uniform.as_entire_binding()),
                entry(1, wgpu::BindingResource::TextureView(&cache.values)),
                entry(2, wgpu::BindingResource::TextureView(&cache.gradients)),
                entry(3, lut.as_entire_binding()),
                entry(4, out.as_entire_binding()),
                entry(5, planes.as_entire_binding()),
                entry(6, pre.as_entire_binding()),
                entry(7, spec.as_entire_binding()),
                entry(8, wgpu::BindingResource::TextureView(&colours.codes)),
                entry(9, linear.as_entire_binding()),
                entry(10, distance.as_entire_binding()),
                entry(11, shadow_head.as_entire_binding()),
                entry(12, light_values.as_entire_binding()),
                entry(13, cache.pages.as_entire_binding()),
            ],
        });
        let mut encoder = device.create_command_encoder(&Default::default());
        {
            let mut pass = encoder.begin_compute_pass(&Default::default());
            pass.set_pipeline(&pipeline);
            pass.set_bind_group(0, &bind, &[]);
            pass.dispatch_workgroups(w.div_ceil(GROUP), h.div_ceil(GROUP), 1);
        }
        self.queue.submit([encoder.finish()]);
        self.finish(scopes)?;
        let bytes = self.read(&out, out_size)?;
        let px: &[[f32; 4]] = bytemuck::cast_slice(&bytes);
        Ok(Image {
            width: w,
            height: h,
            rgb: px.iter().map(|p| [p[0], p[1], p[2]]).collect(),
            alpha: px.iter().map(|p| p[3]).collect(),
            stats: RenderStats::default(),
        })
    }

    /// The light volumes' header and values ([`shadow_tables`]) for a frame of
    /// `march` lit by `shader`: the values uploaded from the CPU's grids or swept on
    /// the GPU; refused for MIP (as the CPU refuses it), for light volumes built for
    /// other lights, and past the adapter's storage buffer binding.
    fn shadow_inputs(
        &mut self,
        (class, march): (&Classification, &LocalMarch),
        (shader, settings): (&Shader, &FrameSettings),
        shadows: Option<LightVolumes<'_>>,
    ) -> Result<(Vec<[f32; 4]>, wgpu::Buffer), GpuError> {
        if shadows.is_some() && march.mode == RenderMode::Mip {
            return Err(GpuError::Unsupported(
                "shadows lighting needs composite or iso mode (MIP is not lit)".into(),
            ));
        }
        let parameter = |e: RenderError| {
            GpuError::Unsupported(match e {
                RenderError::Parameter(line) => line,
                e => e.to_string(),
            })
        };
        let built;
        let shadows = match shadows {
            Some(LightVolumes::Swept(s)) => match class.light_sweeps(shader, settings, &s) {
                Ok(Some(sweeps)) => {
                    let (head, len) = crate::sweep::header(&sweeps, shader.anisotropy());
                    return Ok((head, self.swept(&sweeps, len)?));
                }
                Ok(None) => {
                    built = class
                        .shadow_field(shader, settings, &s, None)
                        .map_err(parameter)?;
                    Some(&built)
                }
                Err(e) => return Err(parameter(e)),
            },
            Some(LightVolumes::Built(s)) => Some(s),
            None => None,
        };
        if shadows.is_some_and(|s| !s.is_for(shader, &march.camera)) {
            return Err(GpuError::Unsupported(
                "the light volumes were built for other lights (or another camera)".into(),
            ));
        }
        let (head, values) = shadow_tables(shadows, shader.anisotropy())?;
        self.need(
            "the largest storage buffer binding",
            self.limits.max_storage_buffer_binding_size,
            values.len() as u64 * 4,
        )?;
        let buffer = self
            .device
            .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("glint light"),
                contents: bytemuck::cast_slice(&values),
                usage: wgpu::BufferUsages::STORAGE,
            });
        Ok((head, buffer))
    }

    /// Uploads `colour`'s 8-bit sRGB codes (as an Rgba8Uint texture) unless they are
    /// on the device already; a one-texel placeholder for a frame without one.
    fn upload_colour(&mut self, colour: Option<&Arc<ColourVolume>>) {
        if let Some(c) = &self.colour {
            let same = match (&c.colour, colour) {
                (None, None) => true,
                (Some(w), Some(a)) => w.upgrade().is_some_and(|f| Arc::ptr_eq(&f, a)),
                _ => false,
            };
            if same {
                return;
            }
        }
        self.colour = None;
        let (dims, codes): ([usize; 3], Vec<[u8; 4]>) = match colour {
            Some(c) => (
                c.dims(),
                c.codes().iter().map(|&[r, g, b]| [r, g, b, 0]).collect(),
            ),
            None => ([1; 3], vec![[0; 4]]),
        };
        let [nx, ny, nz] = dims;
        let size = wgpu::Extent3d {
            width: nx as u32,
            height: ny as u32,
            depth_or_array_layers: nz as u32,
        };
        let format = wgpu::TextureFormat::Rgba8Uint;
        let texture = texture_3d(&self.device, size, format, "glint colours");
        let plane = nx * ny;
        for z0 in (0..nz).step_by(UPLOAD_PLANES) {
            let planes = UPLOAD_PLANES.min(nz - z0);
            let bytes = bytemuck::cast_slice(&codes[z0 * plane..(z0 + planes) * plane]);
            write_slab(
                &texture,
                bytes,
                4,
                ([nx, ny, planes], [0, 0, z0], &self.queue),
            );
        }
        self.colour = Some(ColourCache {
            colour: colour.map(Arc::downgrade),
            codes: texture.create_view(&Default::default()),
        });
    }

    /// The `local` pipeline for the filter and the field's layout, built on first use
    /// (a handle: wgpu's pipelines are shared by reference).
    fn pipeline(&mut self, tricubic: bool, paged: bool) -> wgpu::ComputePipeline {
        let device = &self.device;
        match (tricubic, paged) {
            (false, false) => self.local.clone(),
            (true, false) => self
                .local_tricubic
                .get_or_insert_with(|| crate::adapter::pipeline(device, true, false))
                .clone(),
            (t, true) => self.local_paged[usize::from(t)]
                .get_or_insert_with(|| crate::adapter::pipeline(device, t, true))
                .clone(),
        }
    }

    /// Uploads `field`'s values and gradients unless they are on the device already:
    /// as 3D textures of the field's dims, or, for a field past the texture side
    /// ([`Gpu::texture_side`]), paged into an atlas within it ([`crate::pages`]).
    /// Errors when even the atlas cannot hold it.
    fn upload(&mut self, field: &Arc<Field>) -> Result<(), GpuError> {
        if let Some(c) = &self.field {
            if c.field.upgrade().is_some_and(|f| Arc::ptr_eq(&f, field)) {
                return Ok(());
            }
        }
        let layout = crate::pages::layout(field.dims(), self.texture_side() as usize)?;
        // The old textures go first: two fields need not fit at once.
        self.field = None;
        let grids = field.voxel_grids();
        let (values, gradients, pages) = match layout {
            None => {
                let (v, g) = self.plain_textures(&grids);
                (v, g, vec![0u32; crate::pages::HEADER + 1])
            }
            Some(layout) => {
                let paged =
                    crate::pages::pages(grids.dims, (&grids.values, &grids.gradients), &layout);
                let (v, g) = self.atlas_textures(&paged, &layout);
                (v, g, paged.table)
            }
        };
        let pages = self
            .device
            .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("glint pages"),
                contents: bytemuck::cast_slice(&pages),
                usage: wgpu::BufferUsages::STORAGE,
            });
        self.field = Some(FieldCache {
            field: Arc::downgrade(field),
            values: values.create_view(&Default::default()),
            gradients: gradients.create_view(&Default::default()),
            gradient_scale: grids.gradient_scale,
            pages,
            paged: layout.is_some(),
        });
        Ok(())
    }

    /// The field's values and gradients as 3D textures of its own dims.
    fn plain_textures(&self, grids: &VoxelGrids) -> (wgpu::Texture, wgpu::Texture) {
        let [nx, ny, nz] = grids.dims;
        let size = wgpu::Extent3d {
            width: nx as u32,
            height: ny as u32,
            depth_or_array_layers: nz as u32,
        };
        let (values, gradients) = self.field_textures(size);
        let plane = nx * ny;
        for z0 in (0..nz).step_by(UPLOAD_PLANES) {
            let planes = UPLOAD_PLANES.min(nz - z0);
            let range = z0 * plane..(z0 + planes) * plane;
            let slab = ([nx, ny, planes], [0, 0, z0], &self.queue);
            let values_bytes = bytemuck::cast_slice(&grids.values[range.clone()]);
            write_slab(&values, values_bytes, 4, slab);
            write_slab(
                &gradients,
                bytemuck::cast_slice(&grids.gradients[range]),
                8,
                slab,
            );
        }
        (values, gradients)
    }

    /// A paged field's atlas: each used slot's page written at its place.
    fn atlas_textures(
        &self,
        paged: &crate::pages::Paged,
        layout: &crate::pages::Layout,
    ) -> (wgpu::Texture, wgpu::Texture) {
        let b = layout.side;
        let [sx, sy, _] = layout.slots;
        // Only the rows of slots in use along z.
        let sz = paged.used.div_ceil(sx * sy);
        let size = wgpu::Extent3d {
            width: (sx * b) as u32,
            height: (sy * b) as u32,
            depth_or_array_layers: (sz * b) as u32,
        };
        let (values, gradients) = self.field_textures(size);
        let voxels = b * b * b;
        for s in 0..paged.used {
            let origin = [s % sx, (s / sx) % sy, s / (sx * sy)].map(|x| x * b);
            let range = s * voxels..(s + 1) * voxels;
            let slab = ([b, b, b], origin, &self.queue);
            write_slab(
                &values,
                bytemuck::cast_slice(&paged.values[range.clone()]),
                4,
                slab,
            );
            write_slab(
                &gradients,
                bytemuck::cast_slice(&paged.gradients[range]),
                8,
                slab,
            );
        }
        (values, gradients)
    }

    /// Empty value (R32Float) and gradient (Rgba16Sint) textures of `size`.
    fn field_textures(&self, size: wgpu::Extent3d) -> (wgpu::Texture, wgpu::Texture) {
        let values = texture_3d(
            &self.device,
            size,
            wgpu::TextureFormat::R32Float,
            "glint values",
        );
        let gradients = texture_3d(
            &self.device,
            size,
            wgpu::TextureFormat::Rgba16Sint,
            "glint gradients",
        );
        (values, gradients)
    }
}

fn entry(binding: u32, resource: wgpu::BindingResource<'_>) -> wgpu::BindGroupEntry<'_> {
    wgpu::BindGroupEntry { binding, resource }
}

/// A 3D texture of `size` texels of `format`, sampled by `textureLoad` and written
/// from the host.
fn texture_3d(
    device: &wgpu::Device,
    size: wgpu::Extent3d,
    format: wgpu::TextureFormat,
    label: &str,
) -> wgpu::Texture {
    device.create_texture(&wgpu::TextureDescriptor {
        label: Some(label),
        size,
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D3,
        format,
        usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
        view_formats: &[],
    })
}

/// Writes `planes` planes of `nx` x `ny` texels of `texel` bytes from `bytes` into
/// `texture` from plane `z0`.
fn write_slab(
    texture: &wgpu::Texture,
    bytes: &[u8],
    texel: usize,
    ([nx, ny, planes], [x0, y0, z0], queue): ([usize; 3], [usize; 3], &wgpu::Queue),
) {
    queue.write_texture(
        wgpu::TexelCopyTextureInfo {
            texture,
            mip_level: 0,
            origin: wgpu::Origin3d {
                x: x0 as u32,
                y: y0 as u32,
                z: z0 as u32,
            },
            aspect: wgpu::TextureAspect::All,
        },
        bytes,
        wgpu::TexelCopyBufferLayout {
            offset: 0,
            bytes_per_row: Some((nx * texel) as u32),
            rows_per_image: Some(ny as u32),
        },
        wgpu::Extent3d {
            width: nx as u32,
            height: ny as u32,
            depth_or_array_layers: planes as u32,
        },
    );
}

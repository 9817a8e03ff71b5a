//! The `shadows` model's light volumes swept on the GPU (`sweep.wgsl`): per light, one
//! dispatch per grid plane from the plane nearest the light on (the sweep of
//! `transport/shadows.rs`, whose planes depend each on the one before), into the
//! buffer the march reads, laid out as [`crate::local`]'s `shadow_tables` lays out
//! the CPU's grids.

use std::sync::{Arc, Weak};

use glint_volume::LightSweeps;
use wgpu::util::DeviceExt;

use crate::adapter::{Gpu, GpuError, SweptCache};

/// Grid points per workgroup (`@workgroup_size(64, 1, 1)` in the shader).
const GROUP: u32 = 64;

/// The shader's `Sweep` in bytes (four vec4 of 4-byte words).
const SWEEP_BYTES: u64 = 64;

/// The sweep's compute pipeline.
pub(crate) fn pipeline(device: &wgpu::Device) -> wgpu::ComputePipeline {
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("glint sweep"),
        source: wgpu::ShaderSource::Wgsl(include_str!("sweep.wgsl").into()),
    });
    device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some("glint sweep"),
        layout: None,
        module: &module,
        entry_point: Some("main"),
        compilation_options: Default::default(),
        cache: None,
    })
}

/// The light volumes' header (`shadow` in `local.wgsl`) for `sweeps`, and the length
/// of their values (every light's grid, then the occlusion's).
pub(crate) fn header(sweeps: &LightSweeps, anisotropy: f32) -> (Vec<[f32; 4]>, usize) {
    let mut head = vec![[0.0; 4]; 2];
    let mut n = 0usize;
    for l in &sweeps.lights {
        let (a, len) = (l.axes.map(|x| x as f32), l.len.map(|x| x as f32));
        head.push([a[0], a[1], a[2], n as f32]);
        head.push([len[0], len[1], len[2], 0.0]);
        head.push([l.offset[0], l.offset[1], l.offset[2], 0.0]);
        n += l.len.iter().product::<usize>();
    }
    let d = sweeps.sigma.1.map(|x| x as f32);
    if let Some(o) = &sweeps.occlusion {
        head[1] = [d[0], d[1], d[2], n as f32];
        n += o.len();
    }
    let inv_cell = 1.0 / glint_volume::ShadowField::cell();
    let occlusion = f32::from(u8::from(sweeps.occlusion.is_some()));
    head[0] = [1.0, occlusion, anisotropy, inv_cell];
    (head, n.max(1))
}

/// One `Sweep` (`words_per` words, zero-padded to the uniform offset alignment) per
/// plane of each light of `sweeps` in sweep order, the workgroups of each plane's
/// dispatch, and the index after the last grid (where the occlusion goes).
fn plane_words(sweeps: &LightSweeps, words_per: usize) -> (Vec<u32>, Vec<u32>, u32) {
    let mut words: Vec<u32> = Vec::new();
    let mut dispatches: Vec<u32> = Vec::new();
    let d = sweeps.sigma.1.map(|x| x as u32);
    let mut first = 0u32;
    for l in &sweeps.lights {
        let [a, b, c] = l.axes.map(|x| x as u32);
        let [n0, n1, n2] = l.len.map(|x| x as u32);
        let order: Vec<u32> = if l.from_last {
            (0..n0).rev().collect()
        } else {
            (0..n0).collect()
        };
        for (k, &m) in order.iter().enumerate() {
            let up = if k == 0 || !l.swept {
                None
            } else {
                Some(order[k - 1])
            };
            let mut w = vec![0u32; words_per];
            w[..16].copy_from_slice(&[
                a,
                b,
                c,
                first,
                n0,
                n1,
                n2,
                m,
                l.s.to_bits(),
                l.shift[0].to_bits(),
                l.shift[1].to_bits(),
                if up.is_some() { 1.0f32 } else { 0.0 }.to_bits(),
                d[0],
                d[1],
                d[2],
                up.unwrap_or(0),
            ]);
            words.extend(w);
            dispatches.push((n1 * n2).div_ceil(GROUP));
        }
        first += n0 * n1 * n2;
    }
    (words, dispatches, first)
}

impl SweptCache {
    /// Whether these light volumes were swept from `sweeps`.
    fn holds(&self, sweeps: &LightSweeps) -> bool {
        let alive =
            |w: &Weak<Vec<f32>>, a: &Arc<Vec<f32>>| w.upgrade().is_some_and(|w| Arc::ptr_eq(&w, a));
        let occlusion = match (&self.occlusion, &sweeps.occlusion) {
            (None, None) => true,
            (Some(w), Some(a)) => alive(w, a),
            _ => false,
        };
        occlusion && self.lights == sweeps.lights && alive(&self.sigma, sweeps.sigma.0)
    }
}

impl Gpu {
    /// The light volumes of `sweeps` ([`Gpu::sweep`]): the last ones when they were
    /// swept from the same inputs ([`SweptCache`]), as the CPU keeps its light volumes
    /// across frames.
    pub(crate) fn swept(
        &mut self,
        sweeps: &LightSweeps,
        len: usize,
    ) -> Result<wgpu::Buffer, GpuError> {
        if let Some(c) = &self.lights {
            if c.holds(sweeps) {
                return Ok(c.buffer.clone());
            }
        }
        // The old buffer goes first: two sets need not fit at once.
        self.lights = None;
        let buffer = self.sweep(sweeps, len)?;
        self.lights = Some(SweptCache {
            sigma: Arc::downgrade(sweeps.sigma.0),
            lights: sweeps.lights.clone(),
            occlusion: sweeps.occlusion.as_ref().map(Arc::downgrade),
            buffer: buffer.clone(),
        });
        Ok(buffer)
    }

    /// The number of light-volume sweeps this device has run (a frame that reuses
    /// the last light volumes runs none).
    pub fn sweeps_run(&self) -> u64 {
        self.sweeps_run
    }

    /// The light volumes of `sweeps` swept into a new storage buffer of `len` f32
    /// (the layout of [`header`]), the occlusion copied after the grids.
    pub(crate) fn sweep(
        &mut self,
        sweeps: &LightSweeps,
        len: usize,
    ) -> Result<wgpu::Buffer, GpuError> {
        let bytes = len as u64 * 4;
        let limit = self.limits.max_storage_buffer_binding_size;
        self.need("the largest storage buffer binding", limit, bytes)?;
        if len >= 1 << 24 {
            return Err(GpuError::Unsupported(
                "light volumes of 2^24 values or more".into(),
            ));
        }
        if self.sweep.is_none() {
            self.sweep = Some(pipeline(&self.device));
        }
        self.sweeps_run += 1;
        let pipeline = self.sweep.as_ref().expect("built above");
        let device = &self.device;
        let t = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("glint light"),
            size: bytes,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let sigma = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("glint sigma"),
            contents: bytemuck::cast_slice(&sweeps.sigma.0[..]),
            usage: wgpu::BufferUsages::STORAGE,
        });
        // One `Sweep` per plane, each at the adapter's uniform offset alignment.
        let stride = u64::from(self.limits.min_uniform_buffer_offset_alignment).max(SWEEP_BYTES);
        let words_per = (stride / 4) as usize;
        let (words, dispatches, first) = plane_words(sweeps, words_per);
        if let Some(o) = &sweeps.occlusion {
            self.queue
                .write_buffer(&t, u64::from(first) * 4, bytemuck::cast_slice(o));
        }
        if dispatches.is_empty() {
            return Ok(t);
        }
        let uniform = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("glint sweeps"),
            contents: bytemuck::cast_slice(&words),
            usage: wgpu::BufferUsages::UNIFORM,
        });
        let layout = pipeline.get_bind_group_layout(0);
        let groups: Vec<wgpu::BindGroup> = (0..dispatches.len() as u64)
            .map(|i| {
                device.create_bind_group(&wgpu::BindGroupDescriptor {
                    label: Some("glint sweep"),
                    layout: &layout,
                    entries: &[
                        wgpu::BindGroupEntry {
                            binding: 0,
                            resource: wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                                buffer: &uniform,
                                offset: i * stride,
                                size: wgpu::BufferSize::new(SWEEP_BYTES),
                            }),
                        },
                        wgpu::BindGroupEntry {
                            binding: 1,
                            resource: sigma.as_entire_binding(),
                        },
                        wgpu::BindGroupEntry {
                            binding: 2,
                            resource: t.as_entire_binding(),
                        },
                    ],
                })
            })
            .collect();
        let mut encoder = device.create_command_encoder(&Default::default());
        {
            let mut pass = encoder.begin_compute_pass(&Default::default());
            pass.set_pipeline(pipeline);
            for (group, &n) in groups.iter().zip(&dispatches) {
                pass.set_bind_group(0, group, &[]);
                pass.dispatch_workgroups(n, 1, 1);
            }
        }
        self.queue.submit([encoder.finish()]);
        Ok(t)
    }
}

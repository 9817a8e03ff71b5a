//! The lobe micro-benchmark on the adapter (issue 44 item 5): K_v (one FMA and v
//! multiplies) against `pow` (`exp2(n·log2 c)`, two special-function instructions),
//! each over a buffer of cosines, in lobe evaluations per second.

use std::time::Instant;

use glint_lobe::{Lobe, LobeKind};
use wgpu::util::DeviceExt;

use crate::adapter::{Gpu, GpuError};

/// One variant's measured rate.
#[derive(Clone, Debug, PartialEq)]
pub struct LobeRate {
    /// `pow` or `K_v` with its `v`.
    pub name: String,
    /// Lobe evaluations per second (the best of the timed runs).
    pub evals_per_s: f64,
    /// The mean lobe value over the buffer's first repetition-sums (a checksum, so the
    /// work cannot be skipped, and a sanity check: K_v's is close to pow's).
    pub mean: f64,
}

/// Workgroup size of `lobe_bench.wgsl`.
const GROUP: u32 = 64;

/// Evaluates the lobe of exponent `n` over `count` cosines in `[0.5, 1)`, `reps` times
/// each, as `pow` and as K_v for v = 3..=6, `runs` timed dispatches per variant after
/// one warm-up; returns each variant's best rate. Errors for a count past the
/// adapter's storage limits and for device failures.
pub fn bench_lobes(
    gpu: &Gpu,
    n: f64,
    count: u32,
    reps: u32,
    runs: u32,
) -> Result<Vec<LobeRate>, GpuError> {
    let bytes = u64::from(count) * 4;
    gpu.need(
        "the largest storage buffer binding",
        gpu.limits.max_storage_buffer_binding_size,
        bytes,
    )?;
    let device = &gpu.device;
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("glint lobe bench"),
        source: wgpu::ShaderSource::Wgsl(include_str!("lobe_bench.wgsl").into()),
    });
    let cosines: Vec<f32> = (0..count)
        .map(|i| 0.5 + 0.5 * (i as f32 + 0.5) / count as f32)
        .collect();
    let input = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("cosines"),
        contents: bytemuck::cast_slice(&cosines),
        usage: wgpu::BufferUsages::STORAGE,
    });
    let sums = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("sums"),
        size: bytes,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    });
    let mut variants = vec![("pow".to_string(), 0u32, 0u32, 0.0f64)];
    for v in 3..=6 {
        let lobe = Lobe::<f64>::new(LobeKind::EnergyFit, n, v)
            .map_err(|e| GpuError::Unsupported(e.to_string()))?;
        let a = lobe.coefficient().unwrap_or(0.0);
        variants.push((format!("K_{v}"), 1, v, a));
    }
    let groups = count.div_ceil(GROUP);
    let (gx, gy) = (groups.min(65535), groups.div_ceil(65535));
    let mut rates = Vec::new();
    for (name, form, v, a) in variants {
        let constants = [("FORM", f64::from(form)), ("V", f64::from(v))];
        let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some("glint lobe bench"),
            layout: None,
            module: &module,
            entry_point: Some("main"),
            compilation_options: wgpu::PipelineCompilationOptions {
                constants: &constants,
                ..Default::default()
            },
            cache: None,
        });
        let params = [n as f32, a as f32, reps as f32, count as f32];
        let uniform = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("bench params"),
            contents: bytemuck::cast_slice(&params),
            usage: wgpu::BufferUsages::UNIFORM,
        });
        let bind = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: None,
            layout: &pipeline.get_bind_group_layout(0),
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: uniform.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: input.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 2,
                    resource: sums.as_entire_binding(),
                },
            ],
        });
        let mut best = f64::INFINITY;
        for run in 0..=runs {
            let scopes = gpu.scopes();
            let start = Instant::now();
            let mut encoder = device.create_command_encoder(&Default::default());
            {
                let mut pass = encoder.begin_compute_pass(&Default::default());
                pass.set_pipeline(&pipeline);
                pass.set_bind_group(0, &bind, &[]);
                pass.dispatch_workgroups(gx, gy, 1);
            }
            gpu.queue.submit([encoder.finish()]);
            gpu.finish(scopes)?;
            // Run 0 warms up (pipeline compilation, first touches).
            if run > 0 {
                best = best.min(start.elapsed().as_secs_f64());
            }
        }
        let out = gpu.read(&sums, bytes)?;
        let out: &[f32] = bytemuck::cast_slice(&out);
        let mean =
            out.iter().map(|&s| f64::from(s)).sum::<f64>() / (f64::from(count) * f64::from(reps));
        rates.push(LobeRate {
            name,
            evals_per_s: f64::from(count) * f64::from(reps) / best,
            mean,
        });
    }
    Ok(rates)
}

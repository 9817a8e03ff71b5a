//! Intel Open Image Denoise (the `oidn` cargo feature): its `RT` filter on the linear
//! HDR radiance with the frame's albedo and normal, which are noise-free
//! (`cleanAux`), on a CPU device.
//!
//! Determinism: OIDN's CPU device runs its network with kernels chosen for the CPU's
//! instruction set, on a oneTBB arena of `numThreads` threads; its API documentation
//! promises no bit-identical output. The device is created with `numThreads` set to
//! the Rayon pool's size and thread affinity off (its parameters `numThreads` and
//! `setAffinity`), so runs on one machine at one thread count are meant to repeat;
//! glint promises no more (the built-in `atrous` filter is bit-identical on any
//! thread count).

use std::ffi::CString;

use glint_core::{Image, RenderError};
use glint_volume::PathFeatures;

use super::MAX_RADIANCE;

/// A CPU device with `threads` threads and no affinity, committed.
fn cpu_device(threads: usize) -> Result<oidn::Device, RenderError> {
    let error = |what: &str| RenderError::Parameter(format!("Open Image Denoise: {what}"));
    let threads = i32::try_from(threads.max(1)).unwrap_or(i32::MAX);
    let num_threads = CString::new("numThreads").expect("no NUL");
    let affinity = CString::new("setAffinity").expect("no NUL");
    // SAFETY: the raw calls follow OIDN's C API: a device is created, its parameters
    // set before it is committed, then owned by `oidn::Device` (which releases it);
    // the names are NUL-terminated strings that outlive the calls.
    unsafe {
        let raw = oidn::sys::oidnNewDevice(oidn::sys::OIDNDeviceType_OIDN_DEVICE_TYPE_CPU);
        if raw.is_null() {
            return Err(error("no CPU device (is libOpenImageDenoise_device_cpu beside the library? scripts/fetch-oidn)"));
        }
        oidn::sys::oidnSetDeviceInt(raw, num_threads.as_ptr(), threads);
        oidn::sys::oidnSetDeviceBool(raw, affinity.as_ptr(), false);
        oidn::sys::oidnCommitDevice(raw);
        let device = oidn::Device::from_raw(raw);
        device.get_error().map_err(|e| error(&format!("{e:?}")))?;
        Ok(device)
    }
}

/// `image` denoised by OIDN's `RT` filter (HDR, clean albedo and normal).
pub(super) fn denoise(image: &Image, f: &PathFeatures) -> Result<Image, RenderError> {
    let (w, h) = (image.width as usize, image.height as usize);
    let device = cpu_device(rayon::current_num_threads())?;
    let flat = |v: &[[f32; 3]]| -> Vec<f32> { v.iter().flatten().copied().collect() };
    let color: Vec<f32> = image
        .rgb
        .iter()
        .flatten()
        .map(|&c| {
            if c.is_nan() {
                0.0
            } else {
                c.clamp(0.0, MAX_RADIANCE)
            }
        })
        .collect();
    // Where the ray has no first hit the albedo is 1 (the background is seen as it
    // is) and the normal 0, as OIDN's documentation asks for unlit directions.
    let albedo: Vec<[f32; 3]> = (0..w * h)
        .map(|i| if f.hit(i) { f.albedo[i] } else { [1.0; 3] })
        .collect();
    let (albedo, normal) = (flat(&albedo), flat(&f.normal));
    let mut output = vec![0.0f32; 3 * w * h];
    let mut filter = oidn::RayTracing::try_new(&device)
        .map_err(|e| RenderError::Parameter(format!("Open Image Denoise: {e:?}")))?;
    filter
        .image_dimensions(w, h)
        .hdr(true)
        .clean_aux(true)
        .albedo_normal(&albedo, &normal);
    filter
        .filter(&color, &mut output)
        .map_err(|e| RenderError::Parameter(format!("Open Image Denoise: {e:?}")))?;
    device
        .get_error()
        .map_err(|e| RenderError::Parameter(format!("Open Image Denoise: {e:?}")))?;
    let rgb = output
        .chunks_exact(3)
        .map(|c| [c[0], c[1], c[2]].map(|v| if v.is_finite() { v.max(0.0) } else { 0.0 }))
        .collect();
    Ok(Image {
        width: image.width,
        height: image.height,
        rgb,
        alpha: image.alpha.clone(),
        stats: image.stats,
    })
}

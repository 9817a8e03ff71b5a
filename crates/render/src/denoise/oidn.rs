//! Intel Open Image Denoise: its `RT` filter on the linear HDR radiance with the
//! frame's albedo and normal, which are noise-free (`cleanAux`), on a CPU device.
//!
//! The library is loaded at run time (`libloading`), not linked: every build has
//! `--denoise oidn`, and a machine without the library gets one line naming
//! scripts/fetch-oidn instead of a build that fails to link. The `oidn` crate links
//! at build time only (its `bundled` feature downloads from GitHub, which cannot work
//! here), so the dozen C functions glint calls are declared here, from OIDN 2's
//! `oidn.h` (the same declarations the pyoidn wheel's `capi.py` carries). Searched,
//! in order: `$OIDN_DIR/lib`, `${GLINT_DATA:-~/.cache/glint}/oidn/oidn-2.5.1/lib`
//! (where scripts/fetch-oidn unpacks it), then the system's library path.
//!
//! Determinism: OIDN's CPU device runs its network with kernels chosen for the CPU's
//! instruction set, on a oneTBB arena of `numThreads` threads; its API documentation
//! promises no bit-identical output. The device is created with `numThreads` set to
//! the Rayon pool's size and thread affinity off (its parameters `numThreads` and
//! `setAffinity`), so runs on one machine at one thread count are meant to repeat;
//! glint promises no more (the built-in `atrous` filter is bit-identical on any
//! thread count).

use std::ffi::{c_char, c_int, c_void, CStr};
use std::path::PathBuf;
use std::sync::OnceLock;

use glint_core::{Image, RenderError};
use glint_volume::PathFeatures;

use super::MAX_RADIANCE;

/// The library's file name (its ABI version 2).
#[cfg(target_os = "macos")]
const LIBRARY: &str = "libOpenImageDenoise.2.dylib";
/// The library's file name (its ABI version 2).
#[cfg(target_os = "windows")]
const LIBRARY: &str = "OpenImageDenoise.dll";
/// The library's file name (its ABI version 2).
#[cfg(not(any(target_os = "macos", target_os = "windows")))]
const LIBRARY: &str = "libOpenImageDenoise.so.2";

/// `OIDN_DEVICE_TYPE_CPU`.
const DEVICE_CPU: c_int = 1;
/// `OIDN_FORMAT_FLOAT3`.
const FORMAT_FLOAT3: c_int = 3;

type Device = *mut c_void;
type Filter = *mut c_void;

/// The C functions glint calls, resolved from the loaded library.
struct Api {
    new_device: unsafe extern "C" fn(c_int) -> Device,
    set_device_int: unsafe extern "C" fn(Device, *const c_char, c_int),
    set_device_bool: unsafe extern "C" fn(Device, *const c_char, bool),
    commit_device: unsafe extern "C" fn(Device),
    device_error: unsafe extern "C" fn(Device, *mut *const c_char) -> c_int,
    release_device: unsafe extern "C" fn(Device),
    new_filter: unsafe extern "C" fn(Device, *const c_char) -> Filter,
    #[allow(clippy::type_complexity)]
    set_image: unsafe extern "C" fn(
        Filter,
        *const c_char,
        *mut c_void,
        c_int,
        usize,
        usize,
        usize,
        usize,
        usize,
    ),
    set_filter_bool: unsafe extern "C" fn(Filter, *const c_char, bool),
    commit_filter: unsafe extern "C" fn(Filter),
    execute_filter: unsafe extern "C" fn(Filter),
    release_filter: unsafe extern "C" fn(Filter),
    /// Kept loaded while the function pointers live (for the process).
    _library: libloading::Library,
}

/// Where the library is looked for, in order.
pub(super) fn candidates() -> Vec<PathBuf> {
    let mut paths = Vec::new();
    if let Some(dir) = std::env::var_os("OIDN_DIR").filter(|d| !d.is_empty()) {
        paths.push(PathBuf::from(dir).join("lib").join(LIBRARY));
    }
    let data = std::env::var_os("GLINT_DATA")
        .filter(|d| !d.is_empty())
        .map(PathBuf::from)
        .or_else(|| std::env::var_os("HOME").map(|h| PathBuf::from(h).join(".cache/glint")));
    if let Some(data) = data {
        paths.push(data.join("oidn/oidn-2.5.1/lib").join(LIBRARY));
    }
    // A bare name: the system's library search path.
    paths.push(PathBuf::from(LIBRARY));
    paths
}

/// The one line for a machine without the library: what was looked for, where, and
/// how to get it.
pub(super) fn missing() -> String {
    format!(
        "denoise oidn: Intel Open Image Denoise ({LIBRARY}) was not found in $OIDN_DIR/lib, \
         ${{GLINT_DATA:-~/.cache/glint}}/oidn/oidn-2.5.1/lib or the system's library path; \
         run scripts/fetch-oidn (or use --denoise atrous)"
    )
}

impl Api {
    /// The first of `paths` that loads and has every function; `None` when none does.
    fn load(paths: &[PathBuf]) -> Option<Api> {
        paths.iter().find_map(|p| {
            // SAFETY: loading runs the library's initialisers: OIDN's, which register
            // its devices and touch nothing of this process.
            let library = unsafe { libloading::Library::new(p) }.ok()?;
            Api::resolve(library)
        })
    }

    fn resolve(library: libloading::Library) -> Option<Api> {
        // SAFETY: each symbol is given the type of its declaration in OIDN 2's oidn.h
        // (C enums as c_int, C bool as bool, size_t as usize); the pointers are copied
        // out while `library`, moved into the `Api`, stays loaded.
        unsafe {
            macro_rules! f {
                ($name:literal) => {
                    *library.get($name).ok()?
                };
            }
            Some(Api {
                new_device: f!(b"oidnNewDevice\0"),
                set_device_int: f!(b"oidnSetDeviceInt\0"),
                set_device_bool: f!(b"oidnSetDeviceBool\0"),
                commit_device: f!(b"oidnCommitDevice\0"),
                device_error: f!(b"oidnGetDeviceError\0"),
                release_device: f!(b"oidnReleaseDevice\0"),
                new_filter: f!(b"oidnNewFilter\0"),
                set_image: f!(b"oidnSetSharedFilterImage\0"),
                set_filter_bool: f!(b"oidnSetFilterBool\0"),
                commit_filter: f!(b"oidnCommitFilter\0"),
                execute_filter: f!(b"oidnExecuteFilter\0"),
                release_filter: f!(b"oidnReleaseFilter\0"),
                _library: library,
            })
        }
    }
}

/// The library, loaded on first use (once per process).
fn api() -> Option<&'static Api> {
    static API: OnceLock<Option<Api>> = OnceLock::new();
    API.get_or_init(|| Api::load(&candidates())).as_ref()
}

/// Whether Intel Open Image Denoise can be loaded on this machine.
pub(super) fn available() -> bool {
    api().is_some()
}

/// Whether a library loads from `paths` (for tests of the search).
#[cfg(test)]
pub(super) fn loads_from(paths: &[PathBuf]) -> bool {
    Api::load(paths).is_some()
}

/// A CPU device with `threads` threads and no affinity, committed; released on drop.
struct CpuDevice(&'static Api, Device);

impl Drop for CpuDevice {
    fn drop(&mut self) {
        // SAFETY: the device was created by this API and is released once.
        unsafe { (self.0.release_device)(self.1) }
    }
}

impl CpuDevice {
    fn new(api: &'static Api, threads: usize) -> Result<CpuDevice, RenderError> {
        let threads = c_int::try_from(threads.max(1)).unwrap_or(c_int::MAX);
        // SAFETY: OIDN's C API in its order: a device is created, its parameters set
        // before it is committed; the names are NUL-terminated and outlive the calls.
        unsafe {
            let raw = (api.new_device)(DEVICE_CPU);
            if raw.is_null() {
                return Err(error(
                    "no CPU device (is libOpenImageDenoise_device_cpu beside the library? scripts/fetch-oidn)",
                ));
            }
            let device = CpuDevice(api, raw);
            (api.set_device_int)(raw, c"numThreads".as_ptr(), threads);
            (api.set_device_bool)(raw, c"setAffinity".as_ptr(), false);
            (api.commit_device)(raw);
            device.check()?;
            Ok(device)
        }
    }

    /// The device's pending error as one line, if any.
    fn check(&self) -> Result<(), RenderError> {
        let mut message: *const c_char = std::ptr::null();
        // SAFETY: a live device; OIDN writes a NUL-terminated message (or nothing),
        // valid until the next call on the device, read at once.
        let code = unsafe { (self.0.device_error)(self.1, &mut message) };
        if code == 0 {
            return Ok(());
        }
        let text = if message.is_null() {
            String::new()
        } else {
            // SAFETY: non-null: OIDN's NUL-terminated message, as above.
            unsafe { CStr::from_ptr(message) }
                .to_string_lossy()
                .replace('\n', " ")
        };
        Err(error(&format!("error {code}: {text}")))
    }
}

fn error(what: &str) -> RenderError {
    RenderError::Parameter(format!("Open Image Denoise: {what}"))
}

/// `image` denoised by OIDN's `RT` filter (HDR, clean albedo and normal).
pub(super) fn denoise(image: &Image, f: &PathFeatures) -> Result<Image, RenderError> {
    let api = api().ok_or_else(|| RenderError::Parameter(missing()))?;
    let (w, h) = (image.width as usize, image.height as usize);
    let device = CpuDevice::new(api, rayon::current_num_threads())?;
    let flat = |v: &[[f32; 3]]| -> Vec<f32> { v.iter().flatten().copied().collect() };
    let mut color: Vec<f32> = image
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
    let (mut albedo, mut normal) = (flat(&albedo), flat(&f.normal));
    let mut output = vec![0.0f32; 3 * w * h];
    let images: [(&CStr, &mut Vec<f32>); 4] = [
        (c"color", &mut color),
        (c"albedo", &mut albedo),
        (c"normal", &mut normal),
        (c"output", &mut output),
    ];
    // SAFETY: OIDN's C API in its order on a live device: a filter is created, its
    // images (host memory of w·h packed float triples each, which the CPU device
    // reads and writes in place, alive until the filter is released below) and
    // flags set, committed, executed, released.
    unsafe {
        let filter = (api.new_filter)(device.1, c"RT".as_ptr());
        if filter.is_null() {
            device.check()?;
            return Err(error("no RT filter"));
        }
        for (name, data) in images {
            let ptr = data.as_mut_ptr().cast::<c_void>();
            (api.set_image)(filter, name.as_ptr(), ptr, FORMAT_FLOAT3, w, h, 0, 0, 0);
        }
        (api.set_filter_bool)(filter, c"hdr".as_ptr(), true);
        (api.set_filter_bool)(filter, c"cleanAux".as_ptr(), true);
        (api.commit_filter)(filter);
        (api.execute_filter)(filter);
        (api.release_filter)(filter);
    }
    device.check()?;
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

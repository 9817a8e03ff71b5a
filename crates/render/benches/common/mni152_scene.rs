//! The MNI152 benchmark scene, shared by `benches/mni152.rs` and the examples that
//! time against it (included with `#[path]`: benches and examples are separate crates
//! and the scene does not belong in the library).

use std::path::PathBuf;

use glint_render::{CameraSpec, Input, Phantom, Scene, View};

/// The MNI152 T1 template (path in `GLINT_MNI152`, default
/// `$GLINT_DATA/samples/mni152_t1_09a.nii.gz`, `GLINT_DATA` by default
/// `~/.cache/glint`) with the mr-t2-brain preset, seen
/// from the left, 512x512, step 0.5 voxel; without the template (with a note naming
/// `who` on stderr) the Shepp-Logan phantom at 192^3 with its preset.
pub fn mni152_scene(who: &str) -> Scene {
    let path = std::env::var_os("GLINT_MNI152")
        .map(PathBuf::from)
        .unwrap_or_else(|| glint_testkit::samples_dir().join("mni152_t1_09a.nii.gz"));
    let (input, preset) = if path.is_file() {
        (Input::Path(path), "mr-t2-brain")
    } else {
        eprintln!(
            "{who}: {} is missing; using the phantom (run scripts/fetch-samples)",
            path.display()
        );
        let name = Phantom::SheppLogan;
        (Input::Phantom { name, size: 192 }, "phantom")
    };
    Scene {
        input,
        preset: Some(preset.into()),
        camera: CameraSpec {
            view: View::Left,
            ..Default::default()
        },
        size: [512, 512],
        step: 0.5,
        ..Scene::default()
    }
}

//! A render of an OME-Zarr store streamed into the field's bricks (what
//! `Renderer::open` does with a store) equals the render of the same level read
//! whole into memory, pixel for pixel, on one thread and on two, in the composite,
//! isosurface and surface modes and after a prefilter change (the field rebuilt from
//! the stream).

use std::path::{Path, PathBuf};

use glint_io::zarr::Level;
use glint_io::{open_volume, ReadOptions};
use glint_render::{Image, Input, Prefilter, RenderMode, Renderer, Scene};

fn data(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../io/tests/data/zarr")
        .join(name)
}

/// The image's pixels as bits (NaN compares equal to itself).
fn bits(image: &Image) -> Vec<u32> {
    image
        .rgb
        .iter()
        .flatten()
        .chain(&image.alpha)
        .map(|x| x.to_bits())
        .collect()
}

/// The scene rendered on `threads` rayon threads, streamed and read whole.
fn both(scene: &Scene, options: &ReadOptions, threads: usize) -> (Vec<u32>, Vec<u32>) {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap();
    pool.install(|| {
        let Input::Path(path) = &scene.input else {
            unreachable!()
        };
        let mut streamed = Renderer::open(scene, options).unwrap();
        let volume = open_volume(path, options).unwrap().volume;
        let mut whole = Renderer::from_source(volume, Some(scene.prefilter)).unwrap();
        let a = streamed.render(scene, &|_| {}).unwrap().image;
        let b = whole.render(scene, &|_| {}).unwrap().image;
        (bits(&a), bits(&b))
    })
}

#[test]
fn a_streamed_store_renders_as_the_level_read_whole() {
    let mut one_thread = Vec::new();
    for (store, level) in [
        ("v04-blosc.zarr", 0),
        ("v04-blosc.zarr", 2),
        ("v05-zstd.zarr", 1),
        ("v04-gzip-czyx.zarr", 0),
        ("missing-chunk.zarr", 0),
    ] {
        let options = ReadOptions {
            level: Level::Index(level),
            ..ReadOptions::default()
        };
        for (mode, prefilter) in [
            (RenderMode::Composite, Prefilter::Binomial),
            (RenderMode::Composite, Prefilter::None),
            (RenderMode::Surface, Prefilter::Binomial),
        ] {
            let scene = Scene {
                input: Input::Path(data(store)),
                size: [48, 40],
                mode,
                prefilter,
                ..Scene::default()
            };
            for threads in [1, 2] {
                let (streamed, whole) = both(&scene, &options, threads);
                assert!(
                    streamed == whole,
                    "{store} level {level} {mode:?} {prefilter:?}, {threads} thread(s)"
                );
                if threads == 1 {
                    one_thread.push(streamed);
                } else {
                    assert!(
                        one_thread.last() == Some(&streamed),
                        "{store} level {level}: 1 and 2 threads differ"
                    );
                }
            }
        }
    }
    // The stores' images are not all alike (the comparison can tell them apart).
    assert_ne!(one_thread[0], one_thread[3]);
}

/// A renderer opened for one prefilter rebuilds its field from the stream for another.
#[test]
fn a_prefilter_change_rebuilds_the_field_from_the_stream() {
    let scene = Scene {
        input: Input::Path(data("v05-zstd.zarr")),
        size: [32, 32],
        ..Scene::default()
    };
    let options = ReadOptions::default();
    let mut renderer = Renderer::open(&scene, &options).unwrap();
    let other = Scene {
        prefilter: Prefilter::None,
        ..scene.clone()
    };
    let a = renderer.render(&other, &|_| {}).unwrap().image;
    let mut fresh = Renderer::open(&other, &options).unwrap();
    let b = fresh.render(&other, &|_| {}).unwrap().image;
    assert_eq!(bits(&a), bits(&b));
    assert_eq!(renderer.field().unwrap().prefilter(), Prefilter::None);
}

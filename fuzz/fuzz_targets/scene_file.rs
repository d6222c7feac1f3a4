//! Scene files: parse, split into scene and settings, validate, and build
//! the coarsest discretization of what validates. Must never panic.
#![no_main]

use contactlab::formats::scene_file;
use contactlab::mechanics::discretization::Discretization;
use contactlab::mechanics::mesh_size::MeshSize;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let Ok(file) = scene_file::parse(text) else {
        return;
    };
    let Ok((scene, settings)) = file.split() else {
        return;
    };
    let _ = settings.validate();
    if scene.validate().is_ok() {
        let _ = Discretization::new(&scene, MeshSize::from_level(1).unwrap());
    }
});

//! Fuzzes the STL reader (parse and validate): any bytes give a mesh or an error, never a panic.
#![no_main]
use libfuzzer_sys::fuzz_target;
use vesselmsr::io::{parse_mesh, MeshFormat};

fuzz_target!(|data: &[u8]| {
    let _ = parse_mesh(data, MeshFormat::Stl);
});

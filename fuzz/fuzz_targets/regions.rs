//! Fuzzes the regions JSON reader against a small closed mesh (balls and picked points): any
//! bytes give regions or an error.
#![no_main]
use libfuzzer_sys::fuzz_target;
use vesselmsr::mesh::primitives::icosphere;

fuzz_target!(|data: &[u8]| {
    let mesh = icosphere(1, 1.0, nalgebra::Point3::origin());
    let mut file = tempfile::NamedTempFile::new().expect("a temporary file");
    std::io::Write::write_all(&mut file, data).expect("written");
    let _ = vesselmsr::inpaint::region::read_regions(file.path(), &mesh, &|_| None);
});

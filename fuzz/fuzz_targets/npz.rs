//! Fuzzes the `.npz` archive reader and the MSR checks on top of it (with a 64 MiB member limit,
//! as `--max-memory 64M` would give): any bytes give an archive or an error.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let mut file = tempfile::NamedTempFile::new().expect("a temporary file");
    std::io::Write::write_all(&mut file, data).expect("written");
    let _ = vesselmsr::msr::archive::read_msr_within(file.path(), 64 << 20);
});

//! Fuzzes the Slicer markups reader in both its formats: the same bytes are read as a Markups
//! JSON file (`.mrk.json`) and as a fiducial CSV (`.fcsv`); any bytes give points or an error.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    for suffix in [".mrk.json", ".fcsv"] {
        let mut file = tempfile::Builder::new()
            .suffix(suffix)
            .tempfile()
            .expect("a temporary file");
        std::io::Write::write_all(&mut file, data).expect("written");
        let _ = vesselmsr::io::read_markups(file.path());
    }
});

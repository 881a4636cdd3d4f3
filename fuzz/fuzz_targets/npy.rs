//! Fuzzes the `.npy` array parser of the archives: any bytes give an array or an error.
#![no_main]
use libfuzzer_sys::fuzz_target;
use vesselmsr::io::NpyArray;

fuzz_target!(|data: &[u8]| {
    let _ = NpyArray::from_npy(data);
});

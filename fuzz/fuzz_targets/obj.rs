//! Fuzz target: the obj reader (`Format::Obj`) on arbitrary bytes.
#![no_main]

use libfuzzer_sys::fuzz_target;
use reconbench_geom::io::Format;

fuzz_target!(|data: &[u8]| {
    reconbench_geom_fuzz::check(data, Format::Obj);
});

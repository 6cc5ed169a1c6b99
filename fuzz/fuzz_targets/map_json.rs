//! Line-map JSON files. A map that parses must write out as JSON that parses to the
//! same map.
#![no_main]

use libfuzzer_sys::fuzz_target;
use lrf_lines::LineMap;

fuzz_target!(|data: &[u8]| {
    let Ok(map) = LineMap::from_json_bytes(data) else {
        return;
    };
    let json = map.to_json().expect("a parsed map writes out");
    let again = LineMap::from_json(&json).expect("a written map parses");
    assert_eq!(again.to_json().expect("writes"), json);
});

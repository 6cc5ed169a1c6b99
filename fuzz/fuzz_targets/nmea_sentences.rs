//! A byte stream from an NMEA 0183 GPS receiver, pushed in two pieces (the first byte
//! says where to split). Every fix delivered must be within WGS-84 ranges.
#![no_main]

use ekf_devices::devices::gps::{NmeaReader, Sentence};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Some((&split, stream)) = data.split_first() else {
        return;
    };
    let split = usize::from(split).min(stream.len());
    let mut reader = NmeaReader::new();
    for piece in [&stream[..split], &stream[split..]] {
        for sentence in reader.push(piece) {
            if let Sentence::Fix(fix) = sentence {
                assert!(fix.latitude.abs() <= 90.0, "{fix:?}");
                assert!(fix.longitude.abs() <= 180.0, "{fix:?}");
            }
        }
    }
});

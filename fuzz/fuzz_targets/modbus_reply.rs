//! Bytes on the RS-485 line after a register read, pushed to the MODBUS RTU reply
//! scanner in two pieces (the first byte says where to split). Nothing is counted that
//! was not received.
#![no_main]

use ekf_devices::devices::modbus_base::ReplyScanner;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Some((&split, stream)) = data.split_first() else {
        return;
    };
    let split = usize::from(split).min(stream.len());
    let mut scanner = ReplyScanner::new(1).expect("the request can be built");
    let request_len = scanner.request_frame().len() as u64;
    let done = scanner
        .push(&stream[..split])
        .or_else(|| scanner.push(&stream[split..]));
    if done.is_none() {
        let _ = scanner.give_up();
    }
    let skipped = scanner.garbage_bytes() + scanner.echoes() * request_len;
    assert!(
        skipped <= stream.len() as u64,
        "{skipped} bytes skipped of {}",
        stream.len()
    );
});

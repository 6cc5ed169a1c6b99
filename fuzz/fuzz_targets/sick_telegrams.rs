//! A byte stream from the SICK LMS 2xx, pushed to the telegram parser in two pieces
//! (the first byte says where to split). Every byte must come out exactly once: in a
//! telegram, an ACK/NAK, or a counted discard.
#![no_main]

use ekf_devices::devices::sick::{Event, TelegramParser};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Some((&split, stream)) = data.split_first() else {
        return;
    };
    let split = usize::from(split).min(stream.len());
    let mut parser = TelegramParser::new();
    let mut events = Vec::new();
    for piece in [&stream[..split], &stream[split..]] {
        parser.push(piece);
        events.extend(std::iter::from_fn(|| parser.next_event()));
    }
    events.extend(parser.finish());
    let accounted: usize = events
        .iter()
        .map(|e| match e {
            Event::Telegram(t) => t.encode().len(),
            Event::Ack | Event::Nak => 1,
            Event::Discarded(d) => d.len,
        })
        .sum();
    assert_eq!(accounted, stream.len(), "bytes lost or counted twice");
    assert_eq!(parser.pending(), 0);
});

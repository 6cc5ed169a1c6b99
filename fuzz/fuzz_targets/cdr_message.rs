//! CDR payloads decoded as every supported ROS 2 message type. A payload that decodes
//! must survive encode → decode → encode unchanged (bytes compared, so NaNs count).
#![no_main]

use ekf_ros::ros2::{AnyMessage, SUPPORTED};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    for def in SUPPORTED {
        let Ok(message) = AnyMessage::decode(def.name, data) else {
            continue;
        };
        let Ok(encoded) = message.encode() else {
            continue;
        };
        let again = AnyMessage::decode(def.name, &encoded)
            .unwrap_or_else(|e| panic!("{}: re-encoded message does not decode: {e}", def.name));
        assert_eq!(
            again.encode().ok().as_deref(),
            Some(encoded.as_slice()),
            "{}: encoding is not stable",
            def.name
        );
    }
});

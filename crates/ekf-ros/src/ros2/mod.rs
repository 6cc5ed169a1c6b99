//! ROS 2 messages as plain Rust structs: CDR encoding and decoding, and the `ros2msg`
//! schema text each type is stored with in an MCAP bag.
//!
//! Definitions follow ROS 2 Jazzy, whose wire layout equals Humble's for every type here.
//! Schema texts list constants and fields without comments, in wire order; dependencies
//! follow as `MSG: pkg/Type` sections, each once, as `ros2 bag record` stores them.
//!
//! ```
//! use ekf_ros::ros2::{std_msgs::Header, builtin_interfaces::Time, RosMessage};
//! let header = Header { stamp: Time { sec: 1, nanosec: 2 }, frame_id: "laser".into() };
//! let bytes = header.encode().unwrap();
//! assert_eq!(Header::decode(&bytes).unwrap(), header);
//! assert!(Header::schema_text().starts_with("builtin_interfaces/Time stamp\n"));
//! ```

mod any;
pub mod build;
pub mod builtin_interfaces;
pub mod cdr;
pub mod diagnostic_msgs;
pub mod geometry_msgs;
pub mod nav_msgs;
pub mod schema;
pub mod sensor_msgs;
pub mod std_msgs;
pub mod tf2_msgs;
pub mod visualization_msgs;

pub use any::{AnyMessage, DecodeError, SUPPORTED};
pub use cdr::CdrError;
pub use schema::MsgDef;

/// True if `candidate`, a type name from a bag's schema, names the type whose full name
/// is `full` (`pkg/msg/Type`): in full, or in the short form `pkg/Type` of ROS 1-era and
/// hand-made bags.
pub fn type_name_matches(full: &str, candidate: &str) -> bool {
    candidate == full
        || full
            .split_once("/msg/")
            .is_some_and(|(pkg, ty)| candidate.split_once('/') == Some((pkg, ty)))
}

use serde::{de::DeserializeOwned, Serialize};

/// A ROS 2 message type: its name, its definition and its CDR form.
///
/// The serde impls of these types describe the CDR layout (strings use a bounded reader);
/// encode and decode them through this trait.
pub trait RosMessage: Serialize + DeserializeOwned {
    /// The type's definition; `DEF.name` is the full name, e.g. `sensor_msgs/msg/LaserScan`.
    const DEF: &'static MsgDef;

    /// The full type name as MCAP schema names use it, e.g. `sensor_msgs/msg/LaserScan`.
    fn type_name() -> &'static str {
        Self::DEF.name
    }

    /// The complete `ros2msg` schema text (own definition, then all dependencies).
    fn schema_text() -> String {
        Self::DEF.schema_text()
    }

    /// Encodes as a ROS 2 CDR payload (little-endian, with the encapsulation header).
    fn encode(&self) -> Result<Vec<u8>, CdrError> {
        cdr::encode(Self::DEF.name, self)
    }

    /// Decodes a ROS 2 CDR payload.
    fn decode(bytes: &[u8]) -> Result<Self, CdrError> {
        cdr::decode(Self::DEF.name, bytes)
    }
}

/// A message with a `std_msgs/Header`, whose stamp is the message's time in a bag.
pub trait Stamped {
    /// The message's header.
    fn header(&self) -> &std_msgs::Header;
}

/// Implements [`Stamped`] for types whose `header` field is a [`std_msgs::Header`].
macro_rules! stamped {
    ($($ty:ty),* $(,)?) => {
        $(impl Stamped for $ty {
            fn header(&self) -> &std_msgs::Header {
                &self.header
            }
        })*
    };
}

stamped!(
    geometry_msgs::PoseStamped,
    geometry_msgs::PoseWithCovarianceStamped,
    geometry_msgs::TransformStamped,
    nav_msgs::Odometry,
    sensor_msgs::JointState,
    sensor_msgs::LaserScan,
    sensor_msgs::Imu,
    sensor_msgs::MagneticField,
    sensor_msgs::NavSatFix,
    sensor_msgs::CompressedImage,
    visualization_msgs::Marker,
    diagnostic_msgs::DiagnosticArray,
);

#[cfg(test)]
mod tests {
    use super::type_name_matches;

    #[test]
    fn type_names_match_in_full_or_short_form_only() {
        let full = "geometry_msgs/msg/PoseStamped";
        assert!(type_name_matches(full, full));
        assert!(type_name_matches(full, "geometry_msgs/PoseStamped"));
        assert!(!type_name_matches(full, "geometry_msgs/msg/Pose"));
        assert!(!type_name_matches(full, "nav_msgs/PoseStamped"));
        assert!(!type_name_matches(full, "geometry_msgs/srv/PoseStamped"));
        assert!(!type_name_matches(full, ""));
    }
}

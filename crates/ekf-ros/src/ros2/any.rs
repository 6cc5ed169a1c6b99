//! One enum over every supported message type, to decode a payload given only the type
//! name a bag's schema carries.

use super::{
    builtin_interfaces, diagnostic_msgs, geometry_msgs, nav_msgs, sensor_msgs, std_msgs, tf2_msgs,
    visualization_msgs, CdrError, MsgDef, RosMessage,
};
use thiserror::Error;

/// Why a payload could not be decoded into an [`AnyMessage`].
#[derive(Debug, Error)]
pub enum DecodeError {
    /// The type name is not one of [`SUPPORTED`].
    #[error("unsupported message type `{type_name}`")]
    UnsupportedType {
        /// The type name that was asked for.
        type_name: String,
    },
    /// The bytes are not a valid CDR payload of the type.
    #[error(transparent)]
    Cdr(#[from] CdrError),
}

/// True if `candidate` names `def`, either in full (`pkg/msg/Type`) or short (`pkg/Type`).
fn names(def: &MsgDef, candidate: &str) -> bool {
    super::type_name_matches(def.name, candidate)
}

/// Declares [`AnyMessage`], its dispatch by type name and [`SUPPORTED`] in one list, so the
/// three cannot drift apart.
macro_rules! any_message {
    ($($variant:ident($ty:ty)),* $(,)?) => {
        /// A decoded message of any supported type.
        #[derive(Debug, Clone, PartialEq)]
        // A Marker is large; boxing it would make matching clumsy for one message at a time.
        #[allow(clippy::large_enum_variant)]
        pub enum AnyMessage {
            $(
                #[doc = concat!("`", stringify!($ty), "`.")]
                $variant($ty),
            )*
        }

        /// Definitions of every type [`AnyMessage`] can hold.
        pub const SUPPORTED: &[&MsgDef] = &[$(<$ty as RosMessage>::DEF),*];

        impl AnyMessage {
            /// Decodes `bytes` as the type named `type_name` (`pkg/msg/Type` or `pkg/Type`).
            pub fn decode(type_name: &str, bytes: &[u8]) -> Result<Self, DecodeError> {
                $(
                    if names(<$ty as RosMessage>::DEF, type_name) {
                        return Ok(Self::$variant(<$ty as RosMessage>::decode(bytes)?));
                    }
                )*
                Err(DecodeError::UnsupportedType { type_name: type_name.to_owned() })
            }

            /// The full type name of the held message.
            pub fn type_name(&self) -> &'static str {
                self.def().name
            }

            /// The definition of the held message's type.
            pub fn def(&self) -> &'static MsgDef {
                match self {
                    $(Self::$variant(_) => <$ty as RosMessage>::DEF,)*
                }
            }

            /// Encodes the held message as a CDR payload.
            pub fn encode(&self) -> Result<Vec<u8>, CdrError> {
                match self {
                    $(Self::$variant(m) => m.encode(),)*
                }
            }
        }

        $(
            impl From<$ty> for AnyMessage {
                fn from(m: $ty) -> Self {
                    Self::$variant(m)
                }
            }
        )*
    };
}

any_message!(
    Time(builtin_interfaces::Time),
    Header(std_msgs::Header),
    Point(geometry_msgs::Point),
    Quaternion(geometry_msgs::Quaternion),
    Vector3(geometry_msgs::Vector3),
    Pose(geometry_msgs::Pose),
    PoseStamped(geometry_msgs::PoseStamped),
    PoseWithCovariance(geometry_msgs::PoseWithCovariance),
    PoseWithCovarianceStamped(geometry_msgs::PoseWithCovarianceStamped),
    Twist(geometry_msgs::Twist),
    TwistWithCovariance(geometry_msgs::TwistWithCovariance),
    Transform(geometry_msgs::Transform),
    TransformStamped(geometry_msgs::TransformStamped),
    Odometry(nav_msgs::Odometry),
    JointState(sensor_msgs::JointState),
    LaserScan(sensor_msgs::LaserScan),
    Imu(sensor_msgs::Imu),
    MagneticField(sensor_msgs::MagneticField),
    NavSatStatus(sensor_msgs::NavSatStatus),
    NavSatFix(sensor_msgs::NavSatFix),
    TFMessage(tf2_msgs::TFMessage),
    Marker(visualization_msgs::Marker),
    MarkerArray(visualization_msgs::MarkerArray),
    KeyValue(diagnostic_msgs::KeyValue),
    DiagnosticStatus(diagnostic_msgs::DiagnosticStatus),
    DiagnosticArray(diagnostic_msgs::DiagnosticArray),
);

//! The `ros2msg` schema texts: the exact layout `ros2 bag record` uses, every used type
//! defined once, and field names and order equal to the Rust structs'.

use ekf_cli::ros2::schema::{MsgDef, SEPARATOR};
use ekf_cli::ros2::{
    builtin_interfaces, diagnostic_msgs, geometry_msgs, nav_msgs, sensor_msgs, std_msgs, tf2_msgs,
    visualization_msgs, RosMessage, SUPPORTED,
};
use std::collections::BTreeSet;

const PRIMITIVES: &[&str] = &[
    "bool", "byte", "char", "int8", "uint8", "int16", "uint16", "int32", "uint32", "int64",
    "uint64", "float32", "float64", "string",
];

/// `(type, name)` of each field line of a `.msg` text (constants and comments skipped).
fn fields(text: &str) -> Vec<(String, String)> {
    text.lines()
        .map(|l| l.split('#').next().unwrap_or("").trim())
        .filter(|l| !l.is_empty())
        .filter_map(|l| {
            let mut parts = l.split_whitespace();
            let ty = parts.next()?.to_owned();
            let name = parts.next()?.to_owned();
            (!name.contains('=') && !l.contains('=')).then_some((ty, name))
        })
        .collect()
}

/// The message type of a field type, without array brackets; `None` for primitives.
fn message_type(field_type: &str) -> Option<&str> {
    let base = field_type.split('[').next().unwrap_or(field_type);
    (!PRIMITIVES.contains(&base)).then_some(base)
}

#[test]
fn header_schema_text_is_exact() {
    let expected = format!(
        "builtin_interfaces/Time stamp\nstring frame_id\n{SEPARATOR}\n\
         MSG: builtin_interfaces/Time\nint32 sec\nuint32 nanosec\n"
    );
    assert_eq!(std_msgs::Header::schema_text(), expected);
    assert_eq!(SEPARATOR.len(), 80);
    assert!(SEPARATOR.bytes().all(|b| b == b'='));
}

#[test]
fn every_schema_defines_each_used_type_exactly_once() {
    for def in SUPPORTED {
        let text = def.schema_text();
        let sections: Vec<&str> = text.split(&format!("\n{SEPARATOR}\n")).collect();
        let mut defined = BTreeSet::new();
        for section in &sections[1..] {
            let first = section.lines().next().unwrap();
            let name = first.strip_prefix("MSG: ").expect("MSG: line");
            assert!(
                defined.insert(name.to_owned()),
                "{}: {name} twice",
                def.name
            );
        }
        for section in &sections {
            let body = section.strip_prefix("MSG: ").map_or(*section, |s| {
                s.split_once('\n').map_or("", |(_, rest)| rest)
            });
            for (ty, _) in fields(body) {
                if let Some(ty) = message_type(&ty) {
                    assert!(defined.contains(ty), "{}: {ty} used, not defined", def.name);
                }
            }
        }
        assert!(
            !defined.contains(&def.short_name()),
            "{} defines itself",
            def.name
        );
    }
}

/// Collects the keys of a JSON object in the order they appear.
struct KeysInOrder;

impl<'de> serde::de::Visitor<'de> for KeysInOrder {
    type Value = Vec<String>;

    fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        f.write_str("an object")
    }

    fn visit_map<A: serde::de::MapAccess<'de>>(self, mut map: A) -> Result<Vec<String>, A::Error> {
        let mut keys = Vec::new();
        while let Some(key) = map.next_key::<String>()? {
            map.next_value::<serde::de::IgnoredAny>()?;
            keys.push(key);
        }
        Ok(keys)
    }
}

/// Field names of `value` as serde sees them, in declaration order.
fn serde_field_names<T: serde::Serialize>(value: &T) -> Vec<String> {
    let json = serde_json::to_string(value).unwrap();
    let mut de = serde_json::Deserializer::from_str(&json);
    serde::Deserializer::deserialize_map(&mut de, KeysInOrder).unwrap()
}

/// Checks one struct against its definition's field list.
fn check_fields<T: RosMessage + Default>() {
    let def: &MsgDef = T::DEF;
    let from_text: Vec<String> = fields(def.text).into_iter().map(|(_, n)| n).collect();
    assert_eq!(serde_field_names(&T::default()), from_text, "{}", def.name);
}

#[test]
fn struct_fields_match_schema_fields_in_order() {
    check_fields::<builtin_interfaces::Time>();
    check_fields::<builtin_interfaces::Duration>();
    check_fields::<std_msgs::Header>();
    check_fields::<std_msgs::ColorRGBA>();
    check_fields::<geometry_msgs::Point>();
    check_fields::<geometry_msgs::Vector3>();
    check_fields::<geometry_msgs::Quaternion>();
    check_fields::<geometry_msgs::Pose>();
    check_fields::<geometry_msgs::PoseStamped>();
    check_fields::<geometry_msgs::PoseWithCovariance>();
    check_fields::<geometry_msgs::PoseWithCovarianceStamped>();
    check_fields::<geometry_msgs::Twist>();
    check_fields::<geometry_msgs::TwistWithCovariance>();
    check_fields::<geometry_msgs::Transform>();
    check_fields::<geometry_msgs::TransformStamped>();
    check_fields::<nav_msgs::Odometry>();
    check_fields::<sensor_msgs::JointState>();
    check_fields::<sensor_msgs::LaserScan>();
    check_fields::<sensor_msgs::Imu>();
    check_fields::<sensor_msgs::MagneticField>();
    check_fields::<sensor_msgs::NavSatStatus>();
    check_fields::<sensor_msgs::NavSatFix>();
    check_fields::<sensor_msgs::CompressedImage>();
    check_fields::<tf2_msgs::TFMessage>();
    check_fields::<visualization_msgs::UVCoordinate>();
    check_fields::<visualization_msgs::MeshFile>();
    check_fields::<visualization_msgs::Marker>();
    check_fields::<visualization_msgs::MarkerArray>();
    check_fields::<diagnostic_msgs::KeyValue>();
    check_fields::<diagnostic_msgs::DiagnosticStatus>();
    check_fields::<diagnostic_msgs::DiagnosticArray>();
}

#[test]
fn every_supported_type_has_a_ros2_name() {
    for def in SUPPORTED {
        let parts: Vec<&str> = def.name.split('/').collect();
        assert_eq!(parts.len(), 3, "{}", def.name);
        assert_eq!(parts[1], "msg", "{}", def.name);
    }
}

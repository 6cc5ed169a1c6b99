//! `ros2msg` schema texts as `ros2 bag record` stores them in MCAP: the message's own
//! definition, then every type it uses, each after an 80-`=` line and `MSG: pkg/Type`.

/// One `.msg` definition and the message types its fields use directly.
#[derive(Debug)]
pub struct MsgDef {
    /// Full ROS type name, e.g. `sensor_msgs/msg/LaserScan`.
    pub name: &'static str,
    /// The `.msg` text: constants and fields, one per line, in wire order.
    pub text: &'static str,
    /// Definitions of the message types named in `text` (not transitively).
    pub deps: &'static [&'static MsgDef],
}

/// The line that separates dependency definitions in a `ros2msg` schema.
pub const SEPARATOR: &str =
    "================================================================================";

impl MsgDef {
    /// The type name as written in `MSG:` lines and field types: `pkg/Type`, without `/msg/`.
    pub fn short_name(&self) -> String {
        self.name.replacen("/msg/", "/", 1)
    }

    /// The complete schema text: this definition followed by every transitive dependency,
    /// each exactly once, depth first in field order.
    pub fn schema_text(&self) -> String {
        let mut seen: Vec<&'static str> = Vec::new();
        let mut out = String::from(self.text.trim_end());
        for dep in self.deps {
            append_dependency(dep, &mut seen, &mut out);
        }
        out.push('\n');
        out
    }
}

/// Appends `def` and then its own dependencies, skipping those already written.
fn append_dependency(def: &'static MsgDef, seen: &mut Vec<&'static str>, out: &mut String) {
    if seen.contains(&def.name) {
        return;
    }
    seen.push(def.name);
    out.push('\n');
    out.push_str(SEPARATOR);
    out.push_str("\nMSG: ");
    out.push_str(&def.short_name());
    out.push('\n');
    out.push_str(def.text.trim_end());
    for dep in def.deps {
        append_dependency(dep, seen, out);
    }
}

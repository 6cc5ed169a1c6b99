//! `visualization_msgs`: markers for drawing lines, maps and text in RViz and Foxglove.
//! The definition is the ROS 2 Jazzy one (also Humble's): with texture, UV coordinates
//! (`float32`) and an embedded mesh file.

use super::builtin_interfaces::{Duration, DURATION};
use super::cdr::string;
use super::geometry_msgs::{Point, Pose, Vector3, POINT, POSE, VECTOR3};
use super::schema::MsgDef;
use super::sensor_msgs::{CompressedImage, COMPRESSED_IMAGE};
use super::std_msgs::{ColorRGBA, Header, COLOR_RGBA, HEADER};
use super::RosMessage;
use serde::{Deserialize, Serialize};

/// `visualization_msgs/msg/UVCoordinate`: a texture coordinate in `[0, 1]`.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct UVCoordinate {
    /// Horizontal ratio.
    pub u: f32,
    /// Vertical ratio.
    pub v: f32,
}

/// `visualization_msgs/msg/MeshFile`: a mesh file sent inside the message.
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct MeshFile {
    /// File name, whose extension selects the parser.
    #[serde(with = "string")]
    pub filename: String,
    /// The file's bytes.
    pub data: Vec<u8>,
}

/// `visualization_msgs/msg/Marker`: one shape (arrow, line list, text…) to draw.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct Marker {
    /// Time and frame of the pose and points.
    pub header: Header,
    /// Namespace; with `id` it names the marker.
    #[serde(with = "string")]
    pub ns: String,
    /// Identifier within the namespace.
    pub id: i32,
    /// Shape, one of the type constants ([`Self::ARROW`] …).
    pub r#type: i32,
    /// [`Self::ADD`], [`Self::DELETE`] or [`Self::DELETEALL`].
    pub action: i32,
    /// Pose of the shape.
    pub pose: Pose,
    /// Size (m) along each axis; meaning depends on the type.
    pub scale: Vector3,
    /// Colour of the whole marker.
    pub color: ColorRGBA,
    /// How long the marker lives; zero means forever.
    pub lifetime: Duration,
    /// Whether the marker moves with its frame.
    pub frame_locked: bool,
    /// Points for line, point and list types.
    pub points: Vec<Point>,
    /// Per-point colours, empty or one per point.
    pub colors: Vec<ColorRGBA>,
    /// Texture URI (`embedded://name` for `texture`).
    #[serde(with = "string")]
    pub texture_resource: String,
    /// Embedded texture image.
    pub texture: CompressedImage,
    /// Texture coordinate per vertex.
    pub uv_coordinates: Vec<UVCoordinate>,
    /// Text for [`Self::TEXT_VIEW_FACING`].
    #[serde(with = "string")]
    pub text: String,
    /// Mesh URI for [`Self::MESH_RESOURCE`].
    #[serde(with = "string")]
    pub mesh_resource: String,
    /// Embedded mesh.
    pub mesh_file: MeshFile,
    /// Whether to use the mesh's own materials.
    pub mesh_use_embedded_materials: bool,
}

impl Marker {
    /// Arrow.
    pub const ARROW: i32 = 0;
    /// Box.
    pub const CUBE: i32 = 1;
    /// Sphere (ellipsoid with `scale`).
    pub const SPHERE: i32 = 2;
    /// Cylinder.
    pub const CYLINDER: i32 = 3;
    /// Connected line through `points`.
    pub const LINE_STRIP: i32 = 4;
    /// Separate segments from pairs of `points`.
    pub const LINE_LIST: i32 = 5;
    /// One cube per point.
    pub const CUBE_LIST: i32 = 6;
    /// One sphere per point.
    pub const SPHERE_LIST: i32 = 7;
    /// Points.
    pub const POINTS: i32 = 8;
    /// Text facing the viewer.
    pub const TEXT_VIEW_FACING: i32 = 9;
    /// Mesh from `mesh_resource`.
    pub const MESH_RESOURCE: i32 = 10;
    /// Triangles from triples of `points`.
    pub const TRIANGLE_LIST: i32 = 11;
    /// Arrows along `points` (not implemented by RViz).
    pub const ARROW_STRIP: i32 = 12;
    /// Add or replace the marker.
    pub const ADD: i32 = 0;
    /// Same as [`Self::ADD`].
    pub const MODIFY: i32 = 0;
    /// Delete the marker with this `ns` and `id`.
    pub const DELETE: i32 = 2;
    /// Delete all markers (of `ns`, if set).
    pub const DELETEALL: i32 = 3;
}

/// `visualization_msgs/msg/MarkerArray`: markers published together.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct MarkerArray {
    /// The markers.
    pub markers: Vec<Marker>,
}

/// Definition of `visualization_msgs/msg/UVCoordinate`.
pub const UV_COORDINATE: MsgDef = MsgDef {
    name: "visualization_msgs/msg/UVCoordinate",
    text: "float32 u\nfloat32 v\n",
    deps: &[],
};

/// Definition of `visualization_msgs/msg/MeshFile`.
pub const MESH_FILE: MsgDef = MsgDef {
    name: "visualization_msgs/msg/MeshFile",
    text: "string filename\nuint8[] data\n",
    deps: &[],
};

/// Definition of `visualization_msgs/msg/Marker`.
pub const MARKER: MsgDef = MsgDef {
    name: "visualization_msgs/msg/Marker",
    text: "int32 ARROW=0\nint32 CUBE=1\nint32 SPHERE=2\nint32 CYLINDER=3\nint32 LINE_STRIP=4\n\
           int32 LINE_LIST=5\nint32 CUBE_LIST=6\nint32 SPHERE_LIST=7\nint32 POINTS=8\n\
           int32 TEXT_VIEW_FACING=9\nint32 MESH_RESOURCE=10\nint32 TRIANGLE_LIST=11\n\
           int32 ARROW_STRIP=12\nint32 ADD=0\nint32 MODIFY=0\nint32 DELETE=2\nint32 DELETEALL=3\n\
           std_msgs/Header header\nstring ns\nint32 id\nint32 type\nint32 action\n\
           geometry_msgs/Pose pose\ngeometry_msgs/Vector3 scale\nstd_msgs/ColorRGBA color\n\
           builtin_interfaces/Duration lifetime\nbool frame_locked\n\
           geometry_msgs/Point[] points\nstd_msgs/ColorRGBA[] colors\n\
           string texture_resource\nsensor_msgs/CompressedImage texture\n\
           visualization_msgs/UVCoordinate[] uv_coordinates\nstring text\n\
           string mesh_resource\nvisualization_msgs/MeshFile mesh_file\n\
           bool mesh_use_embedded_materials\n",
    deps: &[
        &HEADER,
        &POSE,
        &VECTOR3,
        &COLOR_RGBA,
        &DURATION,
        &POINT,
        &COMPRESSED_IMAGE,
        &UV_COORDINATE,
        &MESH_FILE,
    ],
};

/// Definition of `visualization_msgs/msg/MarkerArray`.
pub const MARKER_ARRAY: MsgDef = MsgDef {
    name: "visualization_msgs/msg/MarkerArray",
    text: "visualization_msgs/Marker[] markers\n",
    deps: &[&MARKER],
};

impl RosMessage for UVCoordinate {
    const DEF: &'static MsgDef = &UV_COORDINATE;
}
impl RosMessage for MeshFile {
    const DEF: &'static MsgDef = &MESH_FILE;
}
impl RosMessage for Marker {
    const DEF: &'static MsgDef = &MARKER;
}
impl RosMessage for MarkerArray {
    const DEF: &'static MsgDef = &MARKER_ARRAY;
}

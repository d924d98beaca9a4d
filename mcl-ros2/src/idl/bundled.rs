//! The bundled interface definitions: `builtin_interfaces`, `std_msgs`,
//! `std_srvs`, `geometry_msgs` (the common types), `unique_identifier_msgs`
//! and `action_msgs`, as ROS 2 (Humble and later) defines them, comments
//! left out.

/// The kind of a definition file.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    Msg,
    Srv,
    Action,
}

impl Kind {
    /// `msg`, `srv` or `action`: the folder and file extension.
    pub fn as_str(self) -> &'static str {
        match self {
            Kind::Msg => "msg",
            Kind::Srv => "srv",
            Kind::Action => "action",
        }
    }
}

/// (package, kind, name, text) of every bundled definition.
pub const DEFINITIONS: &[(&str, Kind, &str, &str)] = &[
    ("builtin_interfaces", Kind::Msg, "Time", "int32 sec\nuint32 nanosec\n"),
    ("builtin_interfaces", Kind::Msg, "Duration", "int32 sec\nuint32 nanosec\n"),
    ("std_msgs", Kind::Msg, "Bool", "bool data\n"),
    ("std_msgs", Kind::Msg, "Byte", "byte data\n"),
    ("std_msgs", Kind::Msg, "Char", "char data\n"),
    ("std_msgs", Kind::Msg, "Empty", ""),
    ("std_msgs", Kind::Msg, "Float32", "float32 data\n"),
    ("std_msgs", Kind::Msg, "Float64", "float64 data\n"),
    ("std_msgs", Kind::Msg, "Int8", "int8 data\n"),
    ("std_msgs", Kind::Msg, "Int16", "int16 data\n"),
    ("std_msgs", Kind::Msg, "Int32", "int32 data\n"),
    ("std_msgs", Kind::Msg, "Int64", "int64 data\n"),
    ("std_msgs", Kind::Msg, "UInt8", "uint8 data\n"),
    ("std_msgs", Kind::Msg, "UInt16", "uint16 data\n"),
    ("std_msgs", Kind::Msg, "UInt32", "uint32 data\n"),
    ("std_msgs", Kind::Msg, "UInt64", "uint64 data\n"),
    ("std_msgs", Kind::Msg, "String", "string data\n"),
    ("std_msgs", Kind::Msg, "Header", "builtin_interfaces/Time stamp\nstring frame_id\n"),
    ("std_msgs", Kind::Msg, "ColorRGBA", "float32 r\nfloat32 g\nfloat32 b\nfloat32 a\n"),
    ("std_msgs", Kind::Msg, "MultiArrayDimension", "string label\nuint32 size\nuint32 stride\n"),
    ("std_msgs", Kind::Msg, "MultiArrayLayout", "MultiArrayDimension[] dim\nuint32 data_offset\n"),
    ("std_msgs", Kind::Msg, "Float64MultiArray", "MultiArrayLayout layout\nfloat64[] data\n"),
    ("std_msgs", Kind::Msg, "Float32MultiArray", "MultiArrayLayout layout\nfloat32[] data\n"),
    ("std_msgs", Kind::Msg, "Int32MultiArray", "MultiArrayLayout layout\nint32[] data\n"),
    ("std_srvs", Kind::Srv, "Empty", "---\n"),
    ("std_srvs", Kind::Srv, "SetBool", "bool data\n---\nbool success\nstring message\n"),
    ("std_srvs", Kind::Srv, "Trigger", "---\nbool success\nstring message\n"),
    ("geometry_msgs", Kind::Msg, "Point", "float64 x\nfloat64 y\nfloat64 z\n"),
    ("geometry_msgs", Kind::Msg, "Point32", "float32 x\nfloat32 y\nfloat32 z\n"),
    ("geometry_msgs", Kind::Msg, "PointStamped", "std_msgs/Header header\nPoint point\n"),
    ("geometry_msgs", Kind::Msg, "Vector3", "float64 x\nfloat64 y\nfloat64 z\n"),
    ("geometry_msgs", Kind::Msg, "Vector3Stamped", "std_msgs/Header header\nVector3 vector\n"),
    ("geometry_msgs", Kind::Msg, "Quaternion", "float64 x 0\nfloat64 y 0\nfloat64 z 0\nfloat64 w 1\n"),
    ("geometry_msgs", Kind::Msg, "QuaternionStamped", "std_msgs/Header header\nQuaternion quaternion\n"),
    ("geometry_msgs", Kind::Msg, "Pose", "Point position\nQuaternion orientation\n"),
    ("geometry_msgs", Kind::Msg, "Pose2D", "float64 x\nfloat64 y\nfloat64 theta\n"),
    ("geometry_msgs", Kind::Msg, "PoseStamped", "std_msgs/Header header\nPose pose\n"),
    ("geometry_msgs", Kind::Msg, "PoseWithCovariance", "Pose pose\nfloat64[36] covariance\n"),
    (
        "geometry_msgs",
        Kind::Msg,
        "PoseWithCovarianceStamped",
        "std_msgs/Header header\nPoseWithCovariance pose\n",
    ),
    ("geometry_msgs", Kind::Msg, "Polygon", "Point32[] points\n"),
    ("geometry_msgs", Kind::Msg, "Twist", "Vector3 linear\nVector3 angular\n"),
    ("geometry_msgs", Kind::Msg, "TwistStamped", "std_msgs/Header header\nTwist twist\n"),
    ("geometry_msgs", Kind::Msg, "TwistWithCovariance", "Twist twist\nfloat64[36] covariance\n"),
    ("geometry_msgs", Kind::Msg, "Accel", "Vector3 linear\nVector3 angular\n"),
    ("geometry_msgs", Kind::Msg, "Wrench", "Vector3 force\nVector3 torque\n"),
    ("geometry_msgs", Kind::Msg, "WrenchStamped", "std_msgs/Header header\nWrench wrench\n"),
    ("geometry_msgs", Kind::Msg, "Transform", "Vector3 translation\nQuaternion rotation\n"),
    (
        "geometry_msgs",
        Kind::Msg,
        "TransformStamped",
        "std_msgs/Header header\nstring child_frame_id\nTransform transform\n",
    ),
    ("unique_identifier_msgs", Kind::Msg, "UUID", "uint8[16] uuid\n"),
    (
        "action_msgs",
        Kind::Msg,
        "GoalInfo",
        "unique_identifier_msgs/UUID goal_id\nbuiltin_interfaces/Time stamp\n",
    ),
    (
        "action_msgs",
        Kind::Msg,
        "GoalStatus",
        "int8 STATUS_UNKNOWN = 0\nint8 STATUS_ACCEPTED = 1\nint8 STATUS_EXECUTING = 2\nint8 STATUS_CANCELING = 3\n\
         int8 STATUS_SUCCEEDED = 4\nint8 STATUS_CANCELED = 5\nint8 STATUS_ABORTED = 6\nGoalInfo goal_info\nint8 status\n",
    ),
    ("action_msgs", Kind::Msg, "GoalStatusArray", "GoalStatus[] status_list\n"),
    (
        "action_msgs",
        Kind::Srv,
        "CancelGoal",
        "GoalInfo goal_info\n---\nint8 ERROR_NONE = 0\nint8 ERROR_REJECTED = 1\nint8 ERROR_UNKNOWN_GOAL_ID = 2\n\
         int8 ERROR_GOAL_TERMINATED = 3\nint8 return_code\nGoalInfo[] goals_canceling\n",
    ),
];

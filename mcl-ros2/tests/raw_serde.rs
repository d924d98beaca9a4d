//! The dynamic codec agrees with the serde CDR serializer that `rustdds`
//! and `ros2-client` use (`cdr-encoding`): a derived struct serializes to
//! the codec's bytes, and [`RawCdr`] carries the codec's bytes through that
//! serializer and back, also inside a wrapper at an unaligned offset (an
//! action's `GetResult` response: `int8 status`, then the result).

use byteorder::LittleEndian;
use mcl_ros2::cdr::{decode_body, encode, encode_body};
use mcl_ros2::idl::Registry;
use mcl_ros2::raw::RawCdr;
use proptest::prelude::*;
use serde::{Deserialize, Serialize};
use serde_json::json;

#[derive(Serialize)]
struct Time {
    sec: i32,
    nanosec: u32,
}
#[derive(Serialize)]
struct Header {
    stamp: Time,
    frame_id: String,
}
#[derive(Serialize)]
struct Point {
    x: f64,
    y: f64,
    z: f64,
}
#[derive(Serialize)]
struct Quaternion {
    x: f64,
    y: f64,
    z: f64,
    w: f64,
}
#[derive(Serialize)]
struct Pose {
    position: Point,
    orientation: Quaternion,
}
#[derive(Serialize)]
struct PoseStamped {
    header: Header,
    pose: Pose,
}

proptest! {
    #[test]
    fn a_derived_struct_and_the_codec_give_the_same_bytes(
        sec in any::<i32>(), nanosec in any::<u32>(), frame in "[a-z]{0,9}", x in -1e6f64..1e6, w in -1.0f64..1.0,
    ) {
        let typed = PoseStamped {
            header: Header { stamp: Time { sec, nanosec }, frame_id: frame.clone() },
            pose: Pose { position: Point { x, y: 0.0, z: 0.0 }, orientation: Quaternion { x: 0.0, y: 0.0, z: 0.0, w } },
        };
        let serde_bytes = cdr_encoding::to_vec::<_, LittleEndian>(&typed).unwrap();
        let v = json!({
            "header": {"stamp": {"sec": sec, "nanosec": nanosec}, "frame_id": frame},
            "pose": {"position": {"x": x}, "orientation": {"x": 0.0, "y": 0.0, "z": 0.0, "w": w}},
        });
        let r = Registry::bundled();
        let ours = encode(&r, "geometry_msgs/msg/PoseStamped", &v).unwrap();
        prop_assert_eq!(&ours[4..], &serde_bytes[..]);
        // Carried through the serializer unchanged.
        let raw = cdr_encoding::to_vec::<_, LittleEndian>(&RawCdr(ours[4..].to_vec())).unwrap();
        prop_assert_eq!(&raw, &serde_bytes);
        let (back, _) = cdr_encoding::from_bytes::<RawCdr, LittleEndian>(&serde_bytes).unwrap();
        prop_assert_eq!(back.0, serde_bytes);
    }
}

#[derive(Serialize)]
struct Float64 {
    data: f64,
}
#[derive(Serialize)]
struct TypedResult {
    status: i8,
    result: Float64,
}
#[derive(Serialize, Deserialize)]
struct RawResult {
    status: i8,
    result: RawCdr,
}

#[test]
fn a_body_at_an_unaligned_offset_inside_a_wrapper() {
    let r = Registry::bundled();
    let typed =
        cdr_encoding::to_vec::<_, LittleEndian>(&TypedResult { status: 4, result: Float64 { data: 2.5 } }).unwrap();
    let body = encode_body(&r, "std_msgs/msg/Float64", &json!({"data": 2.5}), 1).unwrap();
    let raw = cdr_encoding::to_vec::<_, LittleEndian>(&RawResult { status: 4, result: RawCdr(body) }).unwrap();
    assert_eq!(raw, typed);
    assert_eq!(raw.len(), 16, "status, 7 octets of padding, the float64");
    let (back, _) = cdr_encoding::from_bytes::<RawResult, LittleEndian>(&typed).unwrap();
    assert_eq!(back.status, 4);
    assert_eq!(decode_body(&r, "std_msgs/msg/Float64", &back.result.0, 1).unwrap(), json!({"data": 2.5}));
}

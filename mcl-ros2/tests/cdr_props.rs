//! Properties of the dynamic CDR codec: every value of a type survives
//! encode then decode unchanged, and arbitrary bytes decode to a value or
//! an error, never a panic, for every bundled type.

use mcl_ros2::cdr::{decode, encode};
use mcl_ros2::idl::bundled::{Kind, DEFINITIONS};
use mcl_ros2::idl::Registry;
use proptest::prelude::*;
use serde_json::{json, Value};

const ALL: &str =
    "bool b\nbyte o\nint8 i8\nuint8 u8\nint16 i16\nuint16 u16\nint32 i32\nuint32 u32\nint64 i64\nuint64 u64\n\
float32 f32\nfloat64 f64\nstring s\nstring<=4 bs\nwstring w\nint32[3] fixed\nfloat64[] seq\nint16[<=2] bounded\n\
geometry_msgs/Point p\ngeometry_msgs/Point[] ps\nstd_msgs/Empty e\nstring[] names\n";

fn registry() -> Registry {
    let mut r = Registry::bundled();
    r.add("t", Kind::Msg, "All", ALL).unwrap();
    r.check().unwrap();
    r
}

fn point() -> impl Strategy<Value = Value> {
    (-1e9f64..1e9, -1e9f64..1e9, -1e9f64..1e9).prop_map(|(x, y, z)| json!({"x": x, "y": y, "z": z}))
}

fn all_value() -> impl Strategy<Value = Value> {
    (
        (any::<bool>(), any::<u8>(), any::<i8>(), any::<u8>(), any::<i16>(), any::<u16>(), any::<i32>(), any::<u32>()),
        (any::<i64>(), any::<u64>(), -1e6f32..1e6, any::<f64>().prop_filter("finite", |x| x.is_finite())),
        ("\\PC{0,12}", "[a-z]{0,4}", "\\PC{0,6}"),
        (
            prop::array::uniform3(any::<i32>()),
            prop::collection::vec(-1e3f64..1e3, 0..5),
            prop::collection::vec(any::<i16>(), 0..=2),
        ),
        (point(), prop::collection::vec(point(), 0..3), prop::collection::vec("[a-z ]{0,5}", 0..3)),
    )
        .prop_map(
            |(
                (b, o, i8, u8, i16, u16, i32, u32),
                (i64, u64, f32, f64),
                (s, bs, w),
                (fixed, seq, bounded),
                (p, ps, names),
            )| {
                json!({
                    "b": b, "o": o, "i8": i8, "u8": u8, "i16": i16, "u16": u16, "i32": i32, "u32": u32,
                    "i64": i64, "u64": u64, "f32": f32 as f64, "f64": f64, "s": s.replace('\0', ""), "bs": bs, "w": w,
                    "fixed": fixed, "seq": seq, "bounded": bounded, "p": p, "ps": ps, "e": {}, "names": names,
                })
            },
        )
}

proptest! {
    #[test]
    fn encode_then_decode_gives_the_value_back(v in all_value()) {
        let r = registry();
        let bytes = encode(&r, "t/msg/All", &v).unwrap();
        prop_assert_eq!(&bytes[..4], &[0u8, 1, 0, 0][..]);
        prop_assert_eq!(decode(&r, "t/msg/All", &bytes).unwrap(), v);
    }

    #[test]
    fn hostile_bytes_never_panic(body in prop::collection::vec(any::<u8>(), 0..96), be in any::<bool>()) {
        let r = registry();
        let mut bytes = vec![0, u8::from(!be), 0, 0];
        bytes.extend(body);
        let mut names: Vec<String> = DEFINITIONS
            .iter()
            .filter(|d| d.1 == Kind::Msg)
            .map(|(p, _, n, _)| format!("{p}/msg/{n}"))
            .collect();
        names.push("t/msg/All".into());
        for name in names {
            if let Ok(v) = decode(&r, &name, &bytes) {
                // What decodes encodes again (possibly shorter: padding is not checked).
                prop_assert!(encode(&r, &name, &v).is_ok() || v.to_string().contains("null"), "{name}: {v}");
            }
        }
    }

    #[test]
    fn a_truncated_message_is_an_error(v in all_value(), cut in 0usize..64) {
        let r = registry();
        let bytes = encode(&r, "t/msg/All", &v).unwrap();
        let keep = bytes.len().saturating_sub(cut + 1);
        prop_assert!(decode(&r, "t/msg/All", &bytes[..keep]).is_err());
    }
}

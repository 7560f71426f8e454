//! The ros2msg parser and the CDR reader on schemas and messages built by
//! hand: bounded types, constants, defaults, sequences, fixed arrays,
//! nested types, both byte orders and CDR2's alignment.

use leeway_logs::bag::path::{Extract, FieldPath};
use leeway_logs::bag::plan::Plan;
use leeway_logs::bag::schema::{BaseType, Count, Primitive, Schema};

const SCHEMA: &str = "\
# A comment line, and constants and defaults to skip.
int32 MODE_A=1
string NAME=\"a = b # not a comment\"
string<=8 name  # a bounded string
int32[] counts
float32[3] gains
sequence<geometry_msgs/Vector3, 4> points
Point[<=2] more
uint8 flag 1
float64 value 0.5
int64 big
bool ok
================================================================================
MSG: geometry_msgs/Vector3
float64 x
float64 y
float64 z
================================================================================
MSG: test_msgs/Point
float64 x
";

#[test]
fn the_parser_keeps_fields_and_skips_constants_defaults_and_comments() {
    let schema = Schema::parse("test_msgs/msg/Sample", SCHEMA).expect("parses");
    assert_eq!(schema.root, "test_msgs/Sample");
    let fields = schema.fields("test_msgs/Sample").expect("the root");
    let names: Vec<&str> = fields.iter().map(|f| f.name.as_str()).collect();
    assert_eq!(
        names,
        [
            "name", "counts", "gains", "points", "more", "flag", "value", "big", "ok"
        ]
    );
    assert_eq!(fields[0].base, BaseType::String);
    assert_eq!(
        (fields[1].base.clone(), fields[1].count),
        (BaseType::Primitive(Primitive::Int32), Count::Sequence)
    );
    assert_eq!(fields[2].count, Count::Fixed(3));
    assert_eq!(
        fields[3].base,
        BaseType::Message("geometry_msgs/Vector3".into())
    );
    assert_eq!(fields[3].count, Count::Sequence);
    // A bare type name is in the package of the message that uses it.
    assert_eq!(fields[4].base, BaseType::Message("test_msgs/Point".into()));
}

/// A CDR message writer for either byte order and alignment cap.
struct Message {
    bytes: Vec<u8>,
    big: bool,
    max_align: usize,
}

impl Message {
    fn new(kind: u8) -> Message {
        Message {
            bytes: vec![0, kind, 0, 0],
            big: kind & 1 == 0,
            max_align: if kind >= 6 { 4 } else { 8 },
        }
    }
    fn put(&mut self, le: &[u8]) {
        let align = le.len().min(self.max_align);
        while !(self.bytes.len() - 4).is_multiple_of(align) {
            self.bytes.push(0xAA);
        }
        if self.big {
            self.bytes.extend(le.iter().rev());
        } else {
            self.bytes.extend_from_slice(le);
        }
    }
    fn u32(&mut self, v: u32) {
        self.put(&v.to_le_bytes());
    }
    fn f64(&mut self, v: f64) {
        self.put(&v.to_le_bytes());
    }
}

/// The sample message: name "ship", counts [4, -5], gains [0.5, 1.5, 2.5],
/// points (1,2,3) (4,5,6), more [] , flag 7, value -0.125, big -9, ok true.
fn sample(kind: u8) -> Vec<u8> {
    let mut m = Message::new(kind);
    m.u32(5);
    m.bytes.extend_from_slice(b"ship\0");
    m.u32(2);
    m.put(&4_i32.to_le_bytes());
    m.put(&(-5_i32).to_le_bytes());
    for g in [0.5_f32, 1.5, 2.5] {
        m.put(&g.to_le_bytes());
    }
    m.u32(2);
    for v in 1..=6 {
        m.f64(f64::from(v));
    }
    m.u32(0);
    m.put(&[7]);
    m.f64(-0.125);
    m.put(&(-9_i64).to_le_bytes());
    m.put(&[1]);
    m.bytes
}

fn value(kind: u8, path: &str) -> f64 {
    let schema = Schema::parse("test_msgs/msg/Sample", SCHEMA).expect("parses");
    let field = FieldPath::parse(&format!("/t.{path}")).expect("a path");
    let plan = Plan::compile(&schema, &field.fields, Extract::Number).expect("compiles");
    plan.read(&sample(kind)).expect("reads")
}

#[test]
fn fields_after_strings_sequences_and_arrays_read_in_every_encoding() {
    // CDR little- and big-endian, CDR2 (8-byte values aligned to 4) both ways.
    for kind in [1, 0, 7, 6] {
        assert_eq!(value(kind, "counts[1]"), -5.0, "kind {kind}");
        assert_eq!(value(kind, "gains[2]"), 2.5, "kind {kind}");
        assert_eq!(value(kind, "points[1].y"), 5.0, "kind {kind}");
        assert_eq!(value(kind, "flag"), 7.0, "kind {kind}");
        assert_eq!(value(kind, "value"), -0.125, "kind {kind}");
        assert_eq!(value(kind, "big"), -9.0, "kind {kind}");
    }
}

#[test]
fn a_sequence_shorter_than_the_index_and_a_short_message_are_decode_errors() {
    let schema = Schema::parse("test_msgs/msg/Sample", SCHEMA).expect("parses");
    let plan = |path: &str| {
        let field = FieldPath::parse(&format!("/t.{path}")).expect("a path");
        Plan::compile(&schema, &field.fields, Extract::Number).expect("compiles")
    };
    let error = plan("counts[2]").read(&sample(1)).expect_err("2 counts");
    assert_eq!(
        error.message(),
        "element 2 asked for, and the sequence holds 2"
    );
    let message = sample(1);
    let error = plan("big")
        .read(&message[..message.len() - 4])
        .expect_err("cut");
    assert!(
        error
            .message()
            .starts_with("the message is shorter than its schema"),
        "{error:?}"
    );
    let error = plan("big").read(&[0, 3, 0, 0, 1, 2]).expect_err("PL_CDR");
    assert!(
        error.message().contains("0x0003 is not plain CDR"),
        "{error:?}"
    );
    // `big` is the 8 bytes before the final `bool`: 2^53 + 1 is refused, 2^53 read.
    let mut message = sample(1);
    let at = message.len() - 9;
    message[at..at + 8].copy_from_slice(&((1_i64 << 53) + 1).to_le_bytes());
    let error = plan("big").read(&message).expect_err("not exact");
    assert_eq!(
        error.message(),
        "the integer 9007199254740993 is beyond ±2^53: an f64 cannot hold it exactly"
    );
    message[at..at + 8].copy_from_slice(&(-(1_i64 << 53)).to_le_bytes());
    assert_eq!(plan("big").read(&message), Ok(-9007199254740992.0));
}

#[test]
fn compile_errors_name_the_level_and_its_fields() {
    let schema = Schema::parse("test_msgs/msg/Sample", SCHEMA).expect("parses");
    let compile = |path: &str, extract| {
        let field = FieldPath::parse(path).expect("a path");
        Plan::compile(&schema, &field.fields, extract).expect_err("does not compile")
    };
    let error = compile("/t.points[0].q", Extract::Number);
    assert_eq!(error.message, "`geometry_msgs/Vector3` has no field `q`");
    assert_eq!(
        error.hint,
        "its fields: x (float64), y (float64), z (float64)"
    );
    let error = compile("/t.points", Extract::Number);
    assert!(error.message.contains("`points` is an array"), "{error:?}");
    assert_eq!(error.hint, "pick an element: `points[0]`");
    assert!(
        compile("/t.gains[3]", Extract::Number)
            .message
            .contains("past the end of a float32[3]")
    );
    assert!(
        compile("/t.value[0]", Extract::Number)
            .message
            .contains("not an array")
    );
    assert_eq!(
        compile("/t.name", Extract::Number).message,
        "`name` is a string, not a number"
    );
    assert_eq!(
        compile("/t.ok", Extract::Number).message,
        "`ok` is a bool, not a number"
    );
    assert!(
        compile("/t.value.x", Extract::Number)
            .message
            .contains("is a float64, it has no field `x`")
    );
    assert!(
        compile("/t.points[0]", Extract::Yaw)
            .message
            .contains("neither a `geometry_msgs/Quaternion`")
    );
}

#[test]
fn malformed_schemas_are_errors_not_panics() {
    for (text, expected) in [
        ("float64[x] a", "the array length `x` is not a number"),
        ("float64[2 a", "`[` without its closing `]`"),
        (
            "Missing a",
            "has type `test_msgs/Missing`, which the schema does not define",
        ),
        ("float64", "no field name after the type"),
        ("sequence<int32 a", "`sequence<` without its closing `>`"),
    ] {
        let error = Schema::parse("test_msgs/msg/Bad", text).expect_err(text);
        assert!(error.contains(expected), "{text}: {error}");
    }
}

#[test]
fn field_paths_parse_and_malformed_ones_get_a_hint() {
    let path = FieldPath::parse("/navigation/twist_body.twist.linear.x").expect("valid");
    assert_eq!(path.topic, "/navigation/twist_body");
    let names: Vec<&str> = path.fields.iter().map(|s| s.name.as_str()).collect();
    assert_eq!(names, ["twist", "linear", "x"]);
    let scan = FieldPath::parse("/scan.ranges[3]").expect("valid");
    assert_eq!(scan.fields[0].index, Some(3));
    assert_eq!(scan.to_string(), "/scan.ranges[3]");
    for (text, expected) in [
        ("imu.orientation", "does not start with `/`"),
        ("/imu..x", "an empty field name"),
        ("/imu.x.", "an empty field name"),
        ("/imu.ranges[a]", "the index `a` is not a whole number"),
        ("/imu.ranges[1", "without its closing"),
        ("/im-u.x", "holds `-`"),
        ("/imu.9x", "is not a field name"),
    ] {
        let error = FieldPath::parse(text).expect_err(text);
        assert!(error.message.contains(expected), "{text}: {error:?}");
        assert_eq!(error.location, text);
        assert!(error.hint.contains("/topic.field.subfield"));
    }
}

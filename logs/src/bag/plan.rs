//! A field path compiled against a channel's schema, once: the fields to
//! skip before it and how to read it. Running a plan on a message walks
//! its bytes without allocating.

use std::collections::HashMap;

use super::cdr::{DecodeError, Reader};
use super::path::{Extract, Segment};
use super::schema::{BaseType, Count, Field, Primitive, Schema};

/// How to skip one value of a type.
#[derive(Clone, Debug, PartialEq)]
enum Layout {
    Primitive(Primitive),
    String,
    Struct(Vec<Layout>),
    Fixed(Box<Layout>, usize),
    Sequence(Box<Layout>),
}

/// One step of a plan.
#[derive(Clone, Debug, PartialEq)]
enum Step {
    /// Skip a field.
    Skip(Layout),
    /// Skip to element `index` of an array of `length` elements (`None`: a
    /// sequence, its count read from the message).
    Element {
        element: Layout,
        index: usize,
        length: Option<usize>,
    },
}

/// What the plan reads at the end of its steps.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Leaf {
    Number(Primitive),
    /// A `geometry_msgs/Quaternion` (x, y, z, w), as its yaw.
    Yaw,
}

/// A compiled field path: run it on each message of its channel.
#[derive(Clone, Debug, PartialEq)]
pub struct Plan {
    steps: Vec<Step>,
    leaf: Leaf,
}

/// Why a path does not fit a schema: the problem and a hint.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PlanError {
    /// What is wrong.
    pub message: String,
    /// How to fix it.
    pub hint: String,
}

fn plan_error(message: impl Into<String>, hint: impl Into<String>) -> PlanError {
    PlanError {
        message: message.into(),
        hint: hint.into(),
    }
}

const QUATERNION: &str = "geometry_msgs/Quaternion";

/// Deeper than any real message: a schema that nests further refers to itself.
const MAX_DEPTH: usize = 64;

/// Fields listed in an error, at most.
const LISTED_FIELDS: usize = 24;

/// `fields` of `type_name`, listed for a hint: `x (float64), y (float64)`.
fn list_fields(fields: &[Field]) -> String {
    let mut listed: Vec<String> = fields
        .iter()
        .take(LISTED_FIELDS)
        .map(|field| format!("{} ({})", field.name, field.type_name()))
        .collect();
    if fields.len() > LISTED_FIELDS {
        listed.push(format!("… {} more", fields.len() - LISTED_FIELDS));
    }
    if listed.is_empty() {
        "none".to_string()
    } else {
        listed.join(", ")
    }
}

impl Plan {
    /// Compiles `fields` (outermost first) of the schema's root message,
    /// taken as `extract`. Errors name the level that failed and list its fields.
    pub fn compile(
        schema: &Schema,
        fields: &[Segment],
        extract: Extract,
    ) -> Result<Plan, PlanError> {
        let mut layouts = Layouts {
            schema,
            cache: HashMap::new(),
        };
        let mut steps = Vec::new();
        let mut current = BaseType::Message(schema.root.clone());
        let mut walked = String::new();
        for segment in fields {
            let BaseType::Message(owner) = &current else {
                return Err(plan_error(
                    format!(
                        "`{walked}` is a {}, it has no field `{}`",
                        base_name(&current),
                        segment.name
                    ),
                    "end the path at the number",
                ));
            };
            let owner_fields = layouts.fields(owner)?;
            let Some(k) = owner_fields.iter().position(|f| f.name == segment.name) else {
                return Err(plan_error(
                    format!("`{owner}` has no field `{}`", segment.name),
                    format!("its fields: {}", list_fields(owner_fields)),
                ));
            };
            let field = owner_fields[k].clone();
            for before in &owner_fields[..k] {
                steps.push(Step::Skip(layouts.field(before, 0)?));
            }
            if !walked.is_empty() {
                walked.push('.');
            }
            walked.push_str(&segment.name);
            steps.extend(element_step(&mut layouts, &field, segment, &walked)?);
            current = field.base.clone();
        }
        let leaf = match extract {
            Extract::Number => number_leaf(&current, &walked)?,
            Extract::Yaw => yaw_leaf(&mut layouts, &current, &walked, &mut steps)?,
        };
        Ok(Plan { steps, leaf })
    }

    /// The value in `message` (a whole CDR message, its header included).
    pub fn read(&self, message: &[u8]) -> Result<f64, DecodeError> {
        let mut reader = Reader::new(message)?;
        for step in &self.steps {
            match step {
                Step::Skip(layout) => skip(layout, &mut reader)?,
                Step::Element {
                    element,
                    index,
                    length,
                } => {
                    let length = match length {
                        Some(length) => *length,
                        None => reader.read_u32()? as usize,
                    };
                    if *index >= length {
                        return Err(DecodeError::IndexOutOfRange {
                            index: *index,
                            len: length,
                        });
                    }
                    skip_elements(element, *index, &mut reader)?;
                }
            }
        }
        match self.leaf {
            Leaf::Number(primitive) => reader.read_number(primitive),
            Leaf::Yaw => {
                let x = reader.read_f64()?;
                let y = reader.read_f64()?;
                let z = reader.read_f64()?;
                let w = reader.read_f64()?;
                Ok(yaw(x, y, z, w))
            }
        }
    }
}

/// The heading of quaternion (x, y, z, w): ZYX yaw, rad.
pub fn yaw(x: f64, y: f64, z: f64, w: f64) -> f64 {
    (2.0 * (w * z + x * y)).atan2(1.0 - 2.0 * (y * y + z * z))
}

fn base_name(base: &BaseType) -> String {
    match base {
        BaseType::Primitive(primitive) => primitive.name().to_string(),
        BaseType::String => "string".to_string(),
        BaseType::WString => "wstring".to_string(),
        BaseType::Message(name) => format!("`{name}` message"),
    }
}

/// The step into element `segment.index` of `field`, if it is an array.
fn element_step(
    layouts: &mut Layouts,
    field: &Field,
    segment: &Segment,
    walked: &str,
) -> Result<Option<Step>, PlanError> {
    let element = || Field {
        count: Count::One,
        ..field.clone()
    };
    match (segment.index, field.count) {
        (None, Count::One) => Ok(None),
        (None, _) => Err(plan_error(
            format!("`{walked}` is an array ({})", field.type_name()),
            format!("pick an element: `{walked}[0]`"),
        )),
        (Some(_), Count::One) => Err(plan_error(
            format!("`{walked}` is a {}, not an array", field.type_name()),
            format!("drop the index: `{walked}`"),
        )),
        (Some(index), Count::Fixed(length)) if index >= length => Err(plan_error(
            format!(
                "`{walked}[{index}]` is past the end of a {}",
                field.type_name()
            ),
            format!("indices run from 0 to {}", length.saturating_sub(1)),
        )),
        (Some(index), count) => Ok(Some(Step::Element {
            element: layouts.field(&element(), 0)?,
            index,
            length: match count {
                Count::Fixed(length) => Some(length),
                _ => None,
            },
        })),
    }
}

fn number_leaf(current: &BaseType, walked: &str) -> Result<Leaf, PlanError> {
    match current {
        BaseType::Primitive(primitive) if primitive.is_number() => Ok(Leaf::Number(*primitive)),
        BaseType::Message(name) if name == QUATERNION => Err(plan_error(
            format!("`{walked}` is a `{QUATERNION}`, not a number"),
            "read its heading as a yaw signal, or one of x, y, z, w",
        )),
        BaseType::Message(_) => Err(plan_error(
            format!(
                "`{}` is a {}, not a number",
                if walked.is_empty() {
                    "the topic"
                } else {
                    walked
                },
                base_name(current)
            ),
            "name one of its numeric fields (the next error lists them if the name is wrong)",
        )),
        other => Err(plan_error(
            format!("`{walked}` is a {}, not a number", base_name(other)),
            "signals are numbers: float32/64 or int8 … uint64",
        )),
    }
}

/// Yaw of the quaternion at `current`, or of its field `orientation`.
fn yaw_leaf(
    layouts: &mut Layouts,
    current: &BaseType,
    walked: &str,
    steps: &mut Vec<Step>,
) -> Result<Leaf, PlanError> {
    let not_a_quaternion = || {
        plan_error(
            format!(
                "`{}` is a {}: neither a `{QUATERNION}` nor a message with a field `orientation` of that type",
                if walked.is_empty() {
                    "the topic"
                } else {
                    walked
                },
                base_name(current)
            ),
            "a heading is read from a quaternion, e.g. `/imu.orientation` or `/odom.pose.pose.orientation`",
        )
    };
    let BaseType::Message(name) = current else {
        return Err(not_a_quaternion());
    };
    if name != QUATERNION {
        let fields = layouts.fields(name)?;
        let Some(k) = fields.iter().position(|f| {
            f.name == "orientation"
                && f.count == Count::One
                && f.base == BaseType::Message(QUATERNION.into())
        }) else {
            return Err(not_a_quaternion());
        };
        for before in &fields[..k] {
            steps.push(Step::Skip(layouts.field(before, 0)?));
        }
    }
    let fields = layouts.fields(QUATERNION)?;
    let names: Vec<&str> = fields.iter().map(|f| f.name.as_str()).collect();
    let doubles = fields
        .iter()
        .all(|f| f.base == BaseType::Primitive(Primitive::Float64) && f.count == Count::One);
    if names != ["x", "y", "z", "w"] || !doubles {
        return Err(plan_error(
            format!("the bag's `{QUATERNION}` is not float64 x, y, z, w"),
            "the bag's schema differs from ROS 2's geometry_msgs",
        ));
    }
    Ok(Leaf::Yaw)
}

/// Layouts of a schema's types, each built once.
struct Layouts<'s> {
    schema: &'s Schema,
    cache: HashMap<String, Layout>,
}

impl<'s> Layouts<'s> {
    fn fields(&self, name: &str) -> Result<&'s [Field], PlanError> {
        self.schema.fields(name).ok_or_else(|| {
            plan_error(
                format!("the schema does not define `{name}`"),
                "the bag's schema is incomplete",
            )
        })
    }

    fn field(&mut self, field: &Field, depth: usize) -> Result<Layout, PlanError> {
        let element = match &field.base {
            BaseType::Primitive(primitive) => Layout::Primitive(*primitive),
            BaseType::String => Layout::String,
            BaseType::WString => {
                return Err(plan_error(
                    format!("the path passes a `wstring` field `{}`", field.name),
                    "wstring's encoding depends on the middleware; leeway reads bags without them before the signal",
                ));
            }
            BaseType::Message(name) => self.message(name, depth)?,
        };
        Ok(match field.count {
            Count::One => element,
            Count::Fixed(n) => Layout::Fixed(Box::new(element), n),
            Count::Sequence => Layout::Sequence(Box::new(element)),
        })
    }

    fn message(&mut self, name: &str, depth: usize) -> Result<Layout, PlanError> {
        if let Some(layout) = self.cache.get(name) {
            return Ok(layout.clone());
        }
        if depth > MAX_DEPTH {
            return Err(plan_error(
                format!("`{name}` nests deeper than {MAX_DEPTH} levels"),
                "the schema refers to itself; ROS 2 messages cannot",
            ));
        }
        let fields = self.fields(name)?;
        // rosidl gives a message without fields one `uint8` member, so
        // that it has a size in every middleware.
        let layout = if fields.is_empty() {
            Layout::Primitive(Primitive::Uint8)
        } else {
            Layout::Struct(
                fields
                    .iter()
                    .map(|field| self.field(field, depth + 1))
                    .collect::<Result<_, _>>()?,
            )
        };
        self.cache.insert(name.to_string(), layout.clone());
        Ok(layout)
    }
}

/// Skips one value.
fn skip(layout: &Layout, reader: &mut Reader) -> Result<(), DecodeError> {
    match layout {
        Layout::Primitive(primitive) => {
            reader.align(primitive.size());
            reader.advance(primitive.size())
        }
        Layout::String => {
            let length = reader.read_u32()? as usize;
            reader.advance(length)
        }
        Layout::Struct(fields) => fields.iter().try_for_each(|field| skip(field, reader)),
        Layout::Fixed(element, length) => skip_elements(element, *length, reader),
        Layout::Sequence(element) => {
            let length = reader.read_u32()? as usize;
            skip_elements(element, length, reader)
        }
    }
}

/// Skips `count` values of `element`.
fn skip_elements(element: &Layout, count: usize, reader: &mut Reader) -> Result<(), DecodeError> {
    if count == 0 {
        return Ok(());
    }
    match element {
        // Primitive arrays are contiguous once the first element is aligned.
        Layout::Primitive(primitive) => {
            reader.align(primitive.size());
            reader.advance(count.saturating_mul(primitive.size()))
        }
        _ => {
            // Every element takes a byte at least (an empty message has its
            // `uint8`): a count beyond the bytes left is a short message,
            // found before any loop.
            if count > reader.remaining() {
                return Err(DecodeError::Short {
                    need: count,
                    len: reader.remaining(),
                });
            }
            (0..count).try_for_each(|_| skip(element, reader))
        }
    }
}

//! The `ros2msg` schema of an MCAP channel: the root message's `.msg`
//! definition followed by each dependency's, separated by a line of `=`
//! and a `MSG: pkg/Type` line (what rosbag2 writes).
//!
//! Only what the layout of a CDR message needs is kept: each field's name
//! and type. Constants (`int32 FOO=1`) and default values (`float64 x 0.5`)
//! are skipped; comments too.

use std::collections::HashMap;

/// A ROS 2 primitive type with a fixed CDR size.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Primitive {
    /// `bool`, one byte.
    Bool,
    /// `byte` (an octet).
    Byte,
    /// `char` (one byte).
    Char,
    /// `float32`.
    Float32,
    /// `float64`.
    Float64,
    /// `int8`.
    Int8,
    /// `uint8`.
    Uint8,
    /// `int16`.
    Int16,
    /// `uint16`.
    Uint16,
    /// `int32`.
    Int32,
    /// `uint32`.
    Uint32,
    /// `int64`.
    Int64,
    /// `uint64`.
    Uint64,
}

impl Primitive {
    /// The primitive named `name` in a `.msg` file, if it is one.
    pub fn from_name(name: &str) -> Option<Primitive> {
        Some(match name {
            "bool" => Primitive::Bool,
            "byte" => Primitive::Byte,
            "char" => Primitive::Char,
            "float32" => Primitive::Float32,
            "float64" => Primitive::Float64,
            "int8" => Primitive::Int8,
            "uint8" => Primitive::Uint8,
            "int16" => Primitive::Int16,
            "uint16" => Primitive::Uint16,
            "int32" => Primitive::Int32,
            "uint32" => Primitive::Uint32,
            "int64" => Primitive::Int64,
            "uint64" => Primitive::Uint64,
            _ => return None,
        })
    }

    /// Its name in a `.msg` file.
    pub fn name(self) -> &'static str {
        match self {
            Primitive::Bool => "bool",
            Primitive::Byte => "byte",
            Primitive::Char => "char",
            Primitive::Float32 => "float32",
            Primitive::Float64 => "float64",
            Primitive::Int8 => "int8",
            Primitive::Uint8 => "uint8",
            Primitive::Int16 => "int16",
            Primitive::Uint16 => "uint16",
            Primitive::Int32 => "int32",
            Primitive::Uint32 => "uint32",
            Primitive::Int64 => "int64",
            Primitive::Uint64 => "uint64",
        }
    }

    /// Bytes in CDR (also its alignment).
    pub fn size(self) -> usize {
        match self {
            Primitive::Bool
            | Primitive::Byte
            | Primitive::Char
            | Primitive::Int8
            | Primitive::Uint8 => 1,
            Primitive::Int16 | Primitive::Uint16 => 2,
            Primitive::Float32 | Primitive::Int32 | Primitive::Uint32 => 4,
            Primitive::Float64 | Primitive::Int64 | Primitive::Uint64 => 8,
        }
    }

    /// Whether it is a number leeway reads as a signal (the floats and
    /// integers; not `bool`, `byte` or `char`).
    pub fn is_number(self) -> bool {
        !matches!(self, Primitive::Bool | Primitive::Byte | Primitive::Char)
    }
}

/// The element type of a field.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum BaseType {
    /// A primitive.
    Primitive(Primitive),
    /// `string` or `string<=N` (the bound does not change the encoding).
    String,
    /// `wstring` (its wide characters' size depends on the middleware).
    WString,
    /// A message type, as `pkg/Type`.
    Message(String),
}

/// How many elements a field holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Count {
    /// One.
    One,
    /// `T[N]`: exactly N, no length in the message.
    Fixed(usize),
    /// `T[]`, `T[<=N]` or `sequence<T, N>`: a `uint32` count, then the elements.
    Sequence,
}

/// A field of a message.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Field {
    /// Its name.
    pub name: String,
    /// Its element type.
    pub base: BaseType,
    /// How many elements.
    pub count: Count,
}

impl Field {
    /// The field's type as a `.msg` file writes it.
    pub fn type_name(&self) -> String {
        let base = match &self.base {
            BaseType::Primitive(primitive) => primitive.name().to_string(),
            BaseType::String => "string".to_string(),
            BaseType::WString => "wstring".to_string(),
            BaseType::Message(name) => name.clone(),
        };
        match self.count {
            Count::One => base,
            Count::Fixed(n) => format!("{base}[{n}]"),
            Count::Sequence => format!("{base}[]"),
        }
    }
}

/// A parsed `ros2msg` schema: the root type and every message type it uses.
#[derive(Clone, Debug, PartialEq)]
pub struct Schema {
    /// The root type, as `pkg/Type`.
    pub root: String,
    /// Each message type's fields, by `pkg/Type`.
    pub types: HashMap<String, Vec<Field>>,
}

/// `pkg/msg/Type` → `pkg/Type`, the form `.msg` files refer to types by.
pub fn short_name(name: &str) -> String {
    let parts: Vec<&str> = name.split('/').collect();
    match parts.as_slice() {
        [package, "msg", ty] => format!("{package}/{ty}"),
        _ => name.to_string(),
    }
}

/// ROS 2's builtin types, used when a schema leaves them out.
const BUILTINS: &[(&str, &str)] = &[
    ("builtin_interfaces/Time", "int32 sec\nuint32 nanosec\n"),
    ("builtin_interfaces/Duration", "int32 sec\nuint32 nanosec\n"),
    (
        "std_msgs/Header",
        "builtin_interfaces/Time stamp\nstring frame_id\n",
    ),
];

impl Schema {
    /// Parses the schema of type `name` (`pkg/msg/Type` or `pkg/Type`) from
    /// its `ros2msg` text. Errors say which line is wrong.
    pub fn parse(name: &str, text: &str) -> Result<Schema, String> {
        let root = short_name(name);
        let mut types = HashMap::new();
        let mut current = root.clone();
        let mut lines: Vec<&str> = Vec::new();
        for line in text.lines() {
            let trimmed = line.trim();
            if trimmed.len() >= 3 && trimmed.chars().all(|c| c == '=') {
                let fields = parse_fields(&current, &lines)?;
                types.insert(current.clone(), fields);
                lines.clear();
                current = String::new();
            } else if let Some(dependency) = trimmed.strip_prefix("MSG:") {
                current = short_name(dependency.trim());
            } else {
                lines.push(line);
            }
        }
        if current.is_empty() {
            return Err("the schema ends with a `===` line and no `MSG:` definition".into());
        }
        let fields = parse_fields(&current, &lines)?;
        types.insert(current, fields);
        for (builtin, text) in BUILTINS {
            if !types.contains_key(*builtin) {
                let lines: Vec<&str> = text.lines().collect();
                types.insert(builtin.to_string(), parse_fields(builtin, &lines)?);
            }
        }
        let schema = Schema { root, types };
        schema.check_references()?;
        Ok(schema)
    }

    /// Every message type a field names is defined.
    fn check_references(&self) -> Result<(), String> {
        for (owner, fields) in &self.types {
            for field in fields {
                if let BaseType::Message(name) = &field.base
                    && !self.types.contains_key(name)
                {
                    return Err(format!(
                        "`{owner}.{}` has type `{name}`, which the schema does not define",
                        field.name
                    ));
                }
            }
        }
        Ok(())
    }

    /// The fields of message type `name`.
    pub fn fields(&self, name: &str) -> Option<&[Field]> {
        self.types.get(name).map(Vec::as_slice)
    }
}

/// The fields of one `.msg` definition of type `owner`.
fn parse_fields(owner: &str, lines: &[&str]) -> Result<Vec<Field>, String> {
    let package = owner.split('/').next().unwrap_or_default();
    let mut fields = Vec::new();
    for line in lines {
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        if let Some(field) = parse_line(package, line)
            .map_err(|message| format!("in `{owner}`, line `{line}`: {message}"))?
        {
            fields.push(field);
        }
    }
    Ok(fields)
}

/// One line: a field, or `None` for a constant.
fn parse_line(package: &str, line: &str) -> Result<Option<Field>, String> {
    let (type_text, rest) = split_type(line)?;
    let rest = rest.trim_start();
    let name_len = rest
        .find(|c: char| !(c.is_ascii_alphanumeric() || c == '_'))
        .unwrap_or(rest.len());
    let (name, after) = rest.split_at(name_len);
    if name.is_empty() {
        return Err("no field name after the type".into());
    }
    if after.trim_start().starts_with('=') {
        return Ok(None);
    }
    let (base, count) = parse_type(package, type_text)?;
    Ok(Some(Field {
        name: name.to_string(),
        base,
        count,
    }))
}

/// The type token (which may hold a space inside `sequence<T, N>`) and the rest.
fn split_type(line: &str) -> Result<(&str, &str), String> {
    let from = if line.starts_with("sequence<") {
        line.find('>')
            .ok_or("`sequence<` without its closing `>`")?
    } else {
        0
    };
    let end = line[from..]
        .find(char::is_whitespace)
        .map_or(line.len(), |i| from + i);
    Ok(line.split_at(end))
}

/// A type token: `float64`, `string<=8`, `pkg/Type[3]`, `int32[<=5]`,
/// `sequence<int32, 5>`.
fn parse_type(package: &str, text: &str) -> Result<(BaseType, Count), String> {
    if let Some(inner) = text
        .strip_prefix("sequence<")
        .and_then(|t| t.strip_suffix('>'))
    {
        let element = inner.split(',').next().unwrap_or_default().trim();
        let (base, count) = parse_type(package, element)?;
        if count != Count::One {
            return Err(format!("nested arrays in `{text}` are not valid ROS 2"));
        }
        return Ok((base, Count::Sequence));
    }
    let (element, count) = match text.find('[') {
        Some(open) => {
            let inside = text[open + 1..]
                .strip_suffix(']')
                .ok_or_else(|| format!("`{text}`: `[` without its closing `]`"))?;
            let count = if inside.is_empty() || inside.starts_with("<=") {
                Count::Sequence
            } else {
                Count::Fixed(inside.parse().map_err(|_| {
                    format!("`{text}`: the array length `{inside}` is not a number")
                })?)
            };
            (&text[..open], count)
        }
        None => (text, Count::One),
    };
    Ok((parse_base(package, element)?, count))
}

/// An element type, message names made `pkg/Type`.
fn parse_base(package: &str, text: &str) -> Result<BaseType, String> {
    let unbounded = text.split("<=").next().unwrap_or_default();
    if unbounded == "string" {
        return Ok(BaseType::String);
    }
    if unbounded == "wstring" {
        return Ok(BaseType::WString);
    }
    if let Some(primitive) = Primitive::from_name(text) {
        return Ok(BaseType::Primitive(primitive));
    }
    if text.is_empty()
        || !text
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '/')
    {
        return Err(format!("`{text}` is not a type"));
    }
    Ok(BaseType::Message(match text {
        "Header" => "std_msgs/Header".to_string(),
        name if name.contains('/') => short_name(name),
        name => format!("{package}/{name}"),
    }))
}

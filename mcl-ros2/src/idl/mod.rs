//! ROS 2 interface definitions: the types of a `.msg`, `.srv` or `.action`
//! file ([`parse`]), and the [`Registry`] that resolves nested types by
//! package and name, with the bundled packages ([`bundled`]).

pub mod bundled;
pub mod parse;
pub mod registry;

pub use parse::{parse_action, parse_msg, parse_srv, ParseError};
pub use registry::{Registry, RegistryError};

/// A built-in scalar type of the ROS 2 interface language.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Prim {
    Bool,
    /// `byte`: an octet (decoded as a number 0..=255).
    Byte,
    /// `char`: an octet in ROS 2 (decoded as a number 0..=255).
    Char,
    Float32,
    Float64,
    Int8,
    Uint8,
    Int16,
    Uint16,
    Int32,
    Uint32,
    Int64,
    Uint64,
}

impl Prim {
    /// The scalar named `name` (`duration` and `time` are nested types, not scalars).
    pub fn from_name(name: &str) -> Option<Prim> {
        Some(match name {
            "bool" => Prim::Bool,
            "byte" => Prim::Byte,
            "char" => Prim::Char,
            "float32" => Prim::Float32,
            "float64" => Prim::Float64,
            "int8" => Prim::Int8,
            "uint8" => Prim::Uint8,
            "int16" => Prim::Int16,
            "uint16" => Prim::Uint16,
            "int32" => Prim::Int32,
            "uint32" => Prim::Uint32,
            "int64" => Prim::Int64,
            "uint64" => Prim::Uint64,
            _ => return None,
        })
    }

    /// Size in bytes on the wire, which is also its CDR alignment (XCDR1).
    pub fn size(self) -> usize {
        match self {
            Prim::Bool | Prim::Byte | Prim::Char | Prim::Int8 | Prim::Uint8 => 1,
            Prim::Int16 | Prim::Uint16 => 2,
            Prim::Float32 | Prim::Int32 | Prim::Uint32 => 4,
            Prim::Float64 | Prim::Int64 | Prim::Uint64 => 8,
        }
    }

    /// Whether it is a floating-point type.
    pub fn is_float(self) -> bool {
        matches!(self, Prim::Float32 | Prim::Float64)
    }

    /// Whether it is `bool`.
    pub fn is_bool(self) -> bool {
        self == Prim::Bool
    }

    /// The inclusive range of an integer type, as `i128`.
    pub fn int_range(self) -> Option<(i128, i128)> {
        Some(match self {
            Prim::Byte | Prim::Char | Prim::Uint8 => (0, u8::MAX as i128),
            Prim::Int8 => (i8::MIN as i128, i8::MAX as i128),
            Prim::Int16 => (i16::MIN as i128, i16::MAX as i128),
            Prim::Uint16 => (0, u16::MAX as i128),
            Prim::Int32 => (i32::MIN as i128, i32::MAX as i128),
            Prim::Uint32 => (0, u32::MAX as i128),
            Prim::Int64 => (i64::MIN as i128, i64::MAX as i128),
            Prim::Uint64 => (0, u64::MAX as i128),
            Prim::Bool | Prim::Float32 | Prim::Float64 => return None,
        })
    }
}

/// The element type of a field, before arrays.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum BaseType {
    Prim(Prim),
    /// `string` or `string<=N` (N: the bound in characters).
    String(Option<usize>),
    /// `wstring` or `wstring<=N` (UTF-16 code units on the wire).
    WString(Option<usize>),
    /// A message type by package and name; the package is that of the
    /// defining file when the text does not say (`Header` is
    /// `std_msgs/Header` by the ROS rule).
    Named {
        package: String,
        name: String,
    },
}

impl BaseType {
    /// The full name `pkg/msg/Name` of a named type.
    pub fn full_name(&self) -> Option<String> {
        match self {
            BaseType::Named { package, name } => Some(format!("{package}/msg/{name}")),
            _ => None,
        }
    }
}

/// Whether and how a field is an array.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Array {
    /// A single value.
    No,
    /// `T[N]`: exactly N elements, no length on the wire.
    Fixed(usize),
    /// `T[]`: a sequence.
    Unbounded,
    /// `T[<=N]`: a sequence of at most N elements.
    Bounded(usize),
}

/// One field of a message.
#[derive(Clone, Debug, PartialEq)]
pub struct Field {
    pub name: String,
    pub base: BaseType,
    pub array: Array,
    /// The default value written after the name, as a JSON value.
    pub default: Option<serde_json::Value>,
    /// Line in the definition text (1-based).
    pub line: usize,
}

/// One constant of a message (`int8 FOO=1`).
#[derive(Clone, Debug, PartialEq)]
pub struct Constant {
    pub name: String,
    pub base: BaseType,
    pub value: serde_json::Value,
}

/// A message type: fields in wire order and constants.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Message {
    pub fields: Vec<Field>,
    pub constants: Vec<Constant>,
}

impl Message {
    /// The field named `name`.
    pub fn field(&self, name: &str) -> Option<&Field> {
        self.fields.iter().find(|f| f.name == name)
    }
}

/// A service type: request and response.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Service {
    pub request: Message,
    pub response: Message,
}

/// An action type: goal, result and feedback.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Action {
    pub goal: Message,
    pub result: Message,
    pub feedback: Message,
}

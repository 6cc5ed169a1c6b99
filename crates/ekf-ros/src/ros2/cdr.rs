//! Encoding and decoding of ROS 2 messages as little-endian CDR (XCDR1, what `rmw` sends),
//! including the 4-byte encapsulation header and ROS string rules the `cdr` crate leaves out.

use serde::{de::DeserializeOwned, Serialize};
use thiserror::Error;

/// Why a CDR payload could not be encoded or decoded.
#[derive(Debug, Error)]
pub enum CdrError {
    /// The payload is shorter than the 4-byte encapsulation header.
    #[error("CDR payload of {len} bytes is shorter than the 4-byte encapsulation header")]
    MissingHeader {
        /// Length of the payload in bytes.
        len: usize,
    },
    /// The encapsulation header names a representation other than plain CDR.
    #[error("unsupported CDR encapsulation {header:02x?} (expected plain CDR, 00 00 or 00 01)")]
    Encapsulation {
        /// The first two bytes of the payload.
        header: [u8; 2],
    },
    /// The `cdr` crate rejected the bytes or the value (too short, bad bool, bad UTF-8…).
    #[error("{type_name}: {source}")]
    Codec {
        /// ROS type name of the message, e.g. `sensor_msgs/msg/LaserScan`.
        type_name: &'static str,
        /// The underlying error.
        #[source]
        source: cdr::Error,
    },
}

/// Encodes `value` as a ROS 2 CDR payload: header `00 01 00 00`, then the fields in
/// little-endian order, each aligned to its size relative to the byte after the header.
pub fn encode<T: Serialize>(type_name: &'static str, value: &T) -> Result<Vec<u8>, CdrError> {
    cdr::serialize::<_, _, cdr::CdrLe>(value, cdr::Infinite)
        .map_err(|source| CdrError::Codec { type_name, source })
}

/// Decodes a ROS 2 CDR payload (either byte order). Trailing bytes are allowed, because
/// Fast-DDS pads payloads to a multiple of four.
pub fn decode<T: DeserializeOwned>(type_name: &'static str, bytes: &[u8]) -> Result<T, CdrError> {
    let header: [u8; 4] = bytes
        .get(..4)
        .and_then(|h| h.try_into().ok())
        .ok_or(CdrError::MissingHeader { len: bytes.len() })?;
    if header[0] != 0 || header[1] > 1 {
        return Err(CdrError::Encapsulation {
            header: [header[0], header[1]],
        });
    }
    cdr::deserialize_from(bytes, cdr::Bounded(bytes.len() as u64))
        .map_err(|source| CdrError::Codec { type_name, source })
}

/// Serde adapter for ROS `string` fields: CDR strings carry a `u32` length that counts a
/// terminating NUL. The `cdr` crate allocates the claimed length before checking it against
/// the input, so a corrupt length could request gigabytes; this adapter reads the bytes one
/// by one instead, so memory never exceeds the input size.
pub(crate) mod string {
    use serde::de::{self, DeserializeSeed, SeqAccess, Visitor};
    use serde::{Deserialize, Deserializer, Serializer};
    use std::fmt;

    /// Writes a ROS string (the `cdr` crate adds the NUL and counts it).
    pub fn serialize<S: Serializer>(value: &str, serializer: S) -> Result<S::Ok, S::Error> {
        serializer.serialize_str(value)
    }

    /// Reads a ROS string without trusting its length prefix for allocation.
    pub fn deserialize<'de, D: Deserializer<'de>>(deserializer: D) -> Result<String, D::Error> {
        if deserializer.is_human_readable() {
            return String::deserialize(deserializer);
        }
        deserializer.deserialize_tuple(2, StringVisitor)
    }

    /// The string as `(u32 length, length bytes)`.
    struct StringVisitor;

    impl<'de> Visitor<'de> for StringVisitor {
        type Value = String;

        fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
            f.write_str("a CDR string (u32 length with NUL, bytes)")
        }

        fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<String, A::Error> {
            let len: u32 = seq
                .next_element()?
                .ok_or_else(|| de::Error::custom("missing string length"))?;
            let mut bytes = seq
                .next_element_seed(Octets(len as usize))?
                .ok_or_else(|| de::Error::custom("missing string bytes"))?;
            if bytes.last() == Some(&0) {
                bytes.pop();
            }
            String::from_utf8(bytes).map_err(|e| de::Error::custom(format!("string: {e}")))
        }
    }

    /// `len` raw octets with no length prefix of their own.
    struct Octets(usize);

    impl<'de> DeserializeSeed<'de> for Octets {
        type Value = Vec<u8>;

        fn deserialize<D: Deserializer<'de>>(self, deserializer: D) -> Result<Vec<u8>, D::Error> {
            deserializer.deserialize_tuple(self.0, OctetsVisitor)
        }
    }

    /// Collects octets, growing with the bytes actually present.
    struct OctetsVisitor;

    impl<'de> Visitor<'de> for OctetsVisitor {
        type Value = Vec<u8>;

        fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
            f.write_str("string octets")
        }

        fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Vec<u8>, A::Error> {
            let mut out = Vec::new();
            while let Some(b) = seq.next_element::<u8>()? {
                out.push(b);
            }
            Ok(out)
        }
    }

    /// Serde adapter for ROS `string[]` fields, with the same bounded reading per element.
    pub(crate) mod seq {
        use super::super::string;
        use serde::de::{SeqAccess, Visitor};
        use serde::ser::SerializeSeq;
        use serde::{Deserialize, Deserializer, Serialize, Serializer};
        use std::fmt;

        /// One string, through the bounded adapter.
        #[derive(Serialize, Deserialize)]
        struct Item(#[serde(with = "string")] String);

        /// Writes a `u32` count, then each string.
        pub fn serialize<S: Serializer>(
            value: &[String],
            serializer: S,
        ) -> Result<S::Ok, S::Error> {
            let mut seq = serializer.serialize_seq(Some(value.len()))?;
            for s in value {
                seq.serialize_element(s)?;
            }
            seq.end()
        }

        /// Reads a `u32` count, then each string, growing with the strings actually present.
        pub fn deserialize<'de, D: Deserializer<'de>>(
            deserializer: D,
        ) -> Result<Vec<String>, D::Error> {
            deserializer.deserialize_seq(ItemsVisitor)
        }

        /// Collects the strings of a `string[]`.
        struct ItemsVisitor;

        impl<'de> Visitor<'de> for ItemsVisitor {
            type Value = Vec<String>;

            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("a CDR string sequence")
            }

            fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Vec<String>, A::Error> {
                let mut out = Vec::new();
                while let Some(Item(s)) = seq.next_element()? {
                    out.push(s);
                }
                Ok(out)
            }
        }
    }
}

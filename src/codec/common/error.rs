//! [`FormatError`]: what the shared machinery (and a codec's container
//! parser, where the problem is not specific to the codec) reports about
//! bytes that are not a well-formed file. Each codec's error wraps it
//! (`#[from]`), displaying it unchanged.

/// Bytes that break a file format's rules: codec-neutral, so that the bit
/// coder, the packed arrays and every container parser report the same
/// things the same way.
#[derive(Clone, Debug, thiserror::Error, PartialEq, Eq)]
pub enum FormatError {
    /// The bytes do not start with the format's magic.
    #[error("not a cbvh {format} file (bad magic)")]
    BadMagic {
        /// The format expected (`"RACBVH"`, `"plain BVH"`).
        format: &'static str,
    },
    /// A section (or the header) is shorter than it must be.
    #[error("the {section} section is truncated: need {need} bytes, have {have}")]
    Truncated {
        /// Section name.
        section: &'static str,
        /// Bytes needed.
        need: u64,
        /// Bytes present.
        have: u64,
    },
    /// A header field is inconsistent.
    #[error("bad header field {field}: {why}")]
    Header {
        /// The field.
        field: &'static str,
        /// What is wrong.
        why: String,
    },
    /// A checksum does not match: the file is damaged.
    #[error("the {section} section's checksum does not match: the file is damaged")]
    Checksum {
        /// The section.
        section: &'static str,
    },
    /// A stored value is outside the range its format allows.
    #[error("the {section} section is corrupted: {what} is {value}, more than {limit}")]
    OutOfRange {
        /// The section.
        section: &'static str,
        /// The value's meaning.
        what: &'static str,
        /// The value found.
        value: u64,
        /// The largest value allowed.
        limit: u64,
    },
    /// Coded data that breaks its code's rules (the caller knows where, and
    /// may say so: RACBVH names the cluster).
    #[error("corrupted data: {what}")]
    Corrupt {
        /// What was found.
        what: &'static str,
    },
}

impl FormatError {
    /// A [`FormatError::Header`] error.
    pub fn header(field: &'static str, why: impl Into<String>) -> Self {
        Self::Header {
            field,
            why: why.into(),
        }
    }
}

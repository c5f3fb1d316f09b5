//! clap value parsers for the commands' numeric flags, so that a bad
//! value is refused while the arguments are parsed, before any work, with
//! clap's `invalid value 'V' for '--flag <V>': ...` and a reason that says
//! what the flag takes.
//!
//! - [`whole`]: a whole number within bounds. A flag that takes one is
//!   declared with `allow_negative_numbers = true` as well: without it,
//!   clap reads `--tris -5` as the flag `-5` and suggests `-- -5`, and
//!   `--width -10` as the short flags `-1` and `-0`; with it, the value
//!   reaches the parser, which says that the flag takes a positive number.
//! - [`setting`]: a codec setting's shorthand flag (`--bits`), checked
//!   against the bounds the codec declares for it
//!   ([`Setting`], the registry), not against bounds restated here.
//! - [`vertex_bits`]: `--vertex-bits`, against every codec that quantizes
//!   ([`CodecKind::check_vertex_bits`]).
//!
//! Every parser checks with [`Values::check`], the check a codec's
//! `--set CODEC.KEY=VALUE` goes through, so that both say the same.

use std::ffi::OsStr;
use std::sync::Arc;

use clap::builder::TypedValueParser;

use crate::codec::CodecKind;
use crate::codec::settings::{Setting, Values};

/// `check(flag, value)` for a flag: its value, or why it is refused (the
/// flag is named `--long`).
type Check<T> = dyn Fn(&str, &str) -> Result<T, String> + Send + Sync;

/// A value parser that checks a flag's value with a function of the flag's
/// name and the value; the error is clap's own for a refused value, with
/// the function's reason.
#[derive(Clone)]
pub struct Checked<T> {
    check: Arc<Check<T>>,
}

impl<T> Checked<T> {
    /// The parser that calls `check(flag, value)`.
    pub fn new(check: impl Fn(&str, &str) -> Result<T, String> + Send + Sync + 'static) -> Self {
        Self {
            check: Arc::new(check),
        }
    }
}

impl<T: Clone + Send + Sync + 'static> TypedValueParser for Checked<T> {
    type Value = T;

    fn parse_ref(
        &self,
        cmd: &clap::Command,
        arg: Option<&clap::Arg>,
        value: &OsStr,
    ) -> Result<T, clap::Error> {
        let flag = arg
            .and_then(|a| a.get_long())
            .map_or_else(|| "the value".to_string(), |l| format!("--{l}"));
        let why = match value.to_str() {
            Some(v) => match (self.check)(&flag, v) {
                Ok(t) => return Ok(t),
                Err(why) => why,
            },
            // clap's closure parser below refuses it as not UTF-8.
            None => String::new(),
        };
        // A parser that refuses with `why`: clap formats its error as for
        // any value a parser refuses, naming the flag and the value.
        let refuse = move |_: &str| Err::<T, String>(why.clone());
        refuse.parse_ref(cmd, arg, value)
    }
}

/// `value` checked against `values` for `name`, as a `T`.
fn parse_whole<T: TryFrom<u64>>(name: &str, value: &str, values: Values) -> Result<T, String> {
    values.check(name, value)?;
    value
        .strip_prefix('+')
        .unwrap_or(value)
        .parse::<u64>()
        .ok()
        .and_then(|n| T::try_from(n).ok())
        .ok_or_else(|| format!("{name} takes {values}, not {value}"))
}

/// `value` for `flag` as a whole number from `min` to `max`, or why not
/// (for parsers whose bounds are known only when the flag is given).
pub fn whole_in(flag: &str, value: &str, min: u64, max: u64) -> Result<u64, String> {
    parse_whole(flag, value, Values::whole(min, max))
}

/// A whole number from `min` to `max` (`max` at most `T`'s largest): a
/// negative one is refused as such (declare the flag with
/// `allow_negative_numbers = true`).
pub fn whole<T>(min: u64, max: u64) -> Checked<T>
where
    T: TryFrom<u64> + Clone + Send + Sync + 'static,
{
    debug_assert!(
        T::try_from(max).is_ok(),
        "{max} does not fit the flag's type"
    );
    let values = Values::whole(min, max);
    Checked::new(move |flag, value| parse_whole(flag, value, values))
}

/// The value of a shorthand flag for codec `kind`'s own `setting` (taken
/// from the registry: `RacOptions::BITS` for `--bits`), checked against
/// the values the codec declares for it, as `--set` is.
pub fn setting<T>(kind: CodecKind, setting: Setting) -> Checked<T>
where
    T: TryFrom<u64> + Clone + Send + Sync + 'static,
{
    debug_assert_eq!(kind.setting(setting.key), Some(setting), "{kind}");
    Checked::new(move |_, value| {
        parse_whole(&format!("{kind}.{}", setting.key), value, setting.values)
    })
}

/// `--vertex-bits`: 0 (`f32` vertices) or bits some codec quantizes to
/// ([`CodecKind::check_vertex_bits`]), whether or not that codec is in
/// use; the codecs in use check the bits again for themselves.
pub fn vertex_bits() -> Checked<u32> {
    Checked::new(|flag, value| {
        let bits = parse_whole(flag, value, Values::whole(0, u32::MAX.into()))?;
        CodecKind::check_vertex_bits(bits).map_err(|e| e.to_string())?;
        Ok(bits)
    })
}

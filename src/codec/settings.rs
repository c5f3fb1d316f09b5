//! Codec settings as a front end collects them: the settings every codec
//! may use (the canonical tree's leaf size, bits per vertex coordinate)
//! and each codec's own `CODEC.KEY=VALUE` settings, which the codec itself
//! turns into its options ([`Codec::options_from`](super::Codec::options_from)).
//! A front end never names a codec's fields: adding a codec, or a setting
//! to one, touches no front-end file.
//!
//! Each codec declares its own settings with the values they take
//! ([`Setting`], [`CodecOptions::SETTINGS`]) and the bits per vertex
//! coordinate it quantizes to ([`CodecOptions::VERTEX_BITS`]): the one
//! place their bounds are stated. [`AnyOptions::from_settings`](super::AnyOptions::from_settings)
//! checks every setting against its codec's declaration whether or not
//! that codec is in use (a `--set hcc.nosuch=1` for a plain build is a
//! mistake, not a no-op), and the vertex bits against the codecs that
//! quantize; the codecs in use then check their options as a whole.
//!
//! ```
//! use cbvh::codec::{AnyOptions, CodecKind, Settings};
//!
//! let mut s = Settings::new(1, None);
//! s.set("racbvh.cluster-nodes=1024").unwrap();
//! s.set("hcc.tree-order=true").unwrap();
//! let o = AnyOptions::from_settings(&s, CodecKind::ALL).unwrap();
//! assert_eq!(o.racbvh.cluster_nodes, 1024);
//! assert!(!o.hcc.triangle_ids);
//! // A codec's unknown key, or a bad value, is an error naming it.
//! s.set("racbvh.cluster-size=1024").unwrap();
//! let e = AnyOptions::from_settings(&s, CodecKind::ALL).unwrap_err().to_string();
//! assert!(e.contains("racbvh.cluster-size"), "{e}");
//! // Also for a codec that is not in use, and for a value out of bounds.
//! let mut s = Settings::new(1, None);
//! s.set("racbvh.bits=99").unwrap();
//! let e = AnyOptions::from_settings(&s, &[CodecKind::Plain]).unwrap_err().to_string();
//! assert!(e.contains("racbvh.bits takes a whole number from 8 to 24"), "{e}");
//! ```

use std::str::FromStr;

/// Settings for the codecs from a front end (see the module docs).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Settings {
    /// Most triangles a leaf of the canonical tree holds (1, the papers'
    /// form, by default); a codec that collapses leaves of its own (CLBVH)
    /// makes them hold at least this many.
    pub leaf_size: usize,
    /// Bits per quantized vertex coordinate: `None` for each codec's
    /// default, `Some(0)` to keep `f32` vertices where a codec can (a
    /// codec that always quantizes takes its default).
    pub vertex_bits: Option<u32>,
    own: Vec<Own>,
}

/// One of a codec's own `CODEC.KEY=VALUE` settings, as the codec declares
/// it ([`CodecOptions::SETTINGS`]): its key and the values it takes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Setting {
    /// The key, e.g. `cluster-nodes`.
    pub key: &'static str,
    /// The values it takes.
    pub values: Values,
}

impl Setting {
    /// A setting that takes `true` or `false`.
    pub const fn flag(key: &'static str) -> Self {
        Self {
            key,
            values: Values::Bool,
        }
    }

    /// A setting that takes a whole number from `min` to `max`.
    pub const fn whole(key: &'static str, min: u64, max: u64) -> Self {
        Self {
            key,
            values: Values::whole(min, max),
        }
    }

    /// A setting that takes a power of two from `min` to `max`.
    pub const fn power_of_two(key: &'static str, min: u64, max: u64) -> Self {
        Self {
            key,
            values: Values::Whole {
                min,
                max,
                power_of_two: true,
            },
        }
    }
}

/// The values a setting or a flag takes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Values {
    /// `true` or `false`.
    Bool,
    /// A whole number from `min` to `max`, a power of two if
    /// `power_of_two`.
    Whole {
        /// The least.
        min: u64,
        /// The most.
        max: u64,
        /// Only powers of two.
        power_of_two: bool,
    },
}

impl Values {
    /// A whole number from `min` to `max`.
    pub const fn whole(min: u64, max: u64) -> Self {
        Values::Whole {
            min,
            max,
            power_of_two: false,
        }
    }

    /// Whether the whole number `v` is among the values (`false` for
    /// [`Values::Bool`]).
    pub fn allows(self, v: u64) -> bool {
        match self {
            Values::Bool => false,
            Values::Whole {
                min,
                max,
                power_of_two,
            } => (min..=max).contains(&v) && (!power_of_two || v.is_power_of_two()),
        }
    }

    /// Checks `value`, as a front end gives it, for the setting or flag
    /// `name` (named in the error, which says what `name` takes): a
    /// negative number is refused as such, not as something that is no
    /// number.
    pub fn check(self, name: &str, value: &str) -> Result<(), String> {
        let v = value;
        match self {
            Values::Bool => match v.parse::<bool>() {
                Ok(_) => Ok(()),
                Err(_) => Err(format!("{name} takes {self}, not {value:?}")),
            },
            Values::Whole {
                min,
                max,
                power_of_two,
            } => {
                let digits = |t: &str| !t.is_empty() && t.bytes().all(|b| b.is_ascii_digit());
                if v.strip_prefix('-').is_some_and(digits) {
                    let or_0 = if min == 0 { " or 0" } else { "" };
                    return Err(if max == u64::MAX && min <= 1 && !power_of_two {
                        format!("{v} is negative: {name} takes a positive whole number{or_0}")
                    } else {
                        format!("{v} is negative: {name} takes a positive number{or_0} ({self})")
                    });
                }
                if !digits(v.strip_prefix('+').unwrap_or(v)) {
                    return Err(format!("{value:?} is no whole number: {name} takes {self}"));
                }
                // All digits: a parse error is an overflow.
                match v.parse::<u64>() {
                    Ok(n) if self.allows(n) => Ok(()),
                    _ => Err(format!("{name} takes {self}, not {v}")),
                }
            }
        }
    }
}

/// What the values are, as a noun: "true or false", "a whole number from
/// 8 to 24", "a power of two from 256 to 16384", "a whole number, 1 or
/// more" (no upper bound but the type's).
impl std::fmt::Display for Values {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match *self {
            Values::Bool => f.write_str("true or false"),
            Values::Whole {
                min,
                max,
                power_of_two: true,
            } => write!(f, "a power of two from {min} to {max}"),
            Values::Whole { min, max, .. } if max == u64::MAX => {
                write!(f, "a whole number, {min} or more")
            }
            Values::Whole { min, max, .. } => write!(f, "a whole number from {min} to {max}"),
        }
    }
}

/// One `CODEC.KEY=VALUE`.
#[derive(Clone, Debug, PartialEq, Eq)]
struct Own {
    codec: String,
    key: String,
    value: String,
}

impl Default for Settings {
    fn default() -> Self {
        Self::new(1, None)
    }
}

/// A setting a codec cannot take.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum SettingsError {
    /// Not of the form `CODEC.KEY=VALUE`.
    #[error("`{spec}` is not CODEC.KEY=VALUE (e.g. racbvh.cluster-nodes=4096)")]
    Syntax {
        /// What was given.
        spec: String,
    },
    /// A codec name the registry does not know.
    #[error("`{codec}.{key}`: no codec named {codec:?}; the codecs are {known}")]
    UnknownCodec {
        /// The codec name given.
        codec: String,
        /// The key given with it.
        key: String,
        /// The registry's names.
        known: String,
    },
    /// A key the codec does not have.
    #[error("`{codec}.{key}`: {codec} has no setting {key:?}; its settings are {known}")]
    UnknownKey {
        /// The codec.
        codec: String,
        /// The key given.
        key: String,
        /// The codec's keys (or "none").
        known: String,
    },
    /// A value that does not parse, or that the codec rejects.
    #[error("`{codec}.{key}={value}`: {reason}")]
    BadValue {
        /// The codec.
        codec: String,
        /// The key.
        key: String,
        /// The value given.
        value: String,
        /// Why it is rejected.
        reason: String,
    },
    /// Common vertex bits that no codec quantizes to.
    #[error(
        "vertex bits {bits}: no codec quantizes to {bits} bits ({codecs}); 0 keeps f32 vertices"
    )]
    VertexBits {
        /// The bits given.
        bits: u32,
        /// What the codecs that quantize take, e.g. "racbvh takes a whole
        /// number from 8 to 24, ...".
        codecs: String,
    },
    /// Options the codec rejects as a whole (from the common settings,
    /// or its own settings together).
    #[error("{codec}: {reason}")]
    Invalid {
        /// The codec.
        codec: String,
        /// Why.
        reason: String,
    },
}

/// A codec's options type as front ends make it
/// ([`Codec::Options`](super::Codec::Options) requires it): the codec's own
/// settings with the values they take, the vertex bits it quantizes to,
/// and how those and the common settings the codec uses become its
/// options. The contract refuses a setting under the codec's name with
/// another key, or a value its declaration does not take, before calling
/// `from_settings` ([`Codec::options_from`](super::Codec::options_from)).
pub trait CodecOptions: Sized {
    /// The codec's own `CODEC.KEY=VALUE` settings and the values each
    /// takes (for help texts, the only keys the contract lets through,
    /// and the bounds every front end checks, for every codec).
    const SETTINGS: &'static [Setting];

    /// The bits per vertex coordinate the codec quantizes to (the common
    /// [`Settings::vertex_bits`]), or `None` for a codec that keeps `f32`
    /// vertices whatever they say (the default). Vertex bits that no codec
    /// takes are refused ([`Settings::vertex_bits`] 0 keeps `f32`).
    const VERTEX_BITS: Option<Values> = None;

    /// The options from `settings`: a bad value, or options the codec
    /// would reject, is an error naming them, before any work.
    fn from_settings(settings: &Settings) -> Result<Self, SettingsError>;
}

/// The options of a codec with nothing to choose (plain): no keys.
impl CodecOptions for () {
    const SETTINGS: &'static [Setting] = &[];

    fn from_settings(_: &Settings) -> Result<(), SettingsError> {
        Ok(())
    }
}

impl Settings {
    /// The common settings, and no codec's own.
    pub fn new(leaf_size: usize, vertex_bits: Option<u32>) -> Self {
        Self {
            leaf_size,
            vertex_bits,
            own: Vec::new(),
        }
    }

    /// Adds `CODEC.KEY=VALUE` (as a command line gives it); a later value
    /// of the same key replaces an earlier one. The codec and key are
    /// checked when the options are made ([`Codec::options_from`](super::Codec::options_from)).
    pub fn set(&mut self, spec: &str) -> Result<(), SettingsError> {
        let syntax = || SettingsError::Syntax { spec: spec.into() };
        let (name, value) = spec.split_once('=').ok_or_else(syntax)?;
        let (codec, key) = name.split_once('.').ok_or_else(syntax)?;
        if codec.is_empty() || key.is_empty() || value.is_empty() {
            return Err(syntax());
        }
        self.own.retain(|o| !(o.codec == codec && o.key == key));
        self.own.push(Own {
            codec: codec.into(),
            key: key.into(),
            value: value.into(),
        });
        Ok(())
    }

    /// The codecs named by the own settings, each with the first key given
    /// for it.
    pub(crate) fn named_codecs(&self) -> impl Iterator<Item = (&str, &str)> {
        self.own.iter().map(|o| (o.codec.as_str(), o.key.as_str()))
    }

    /// The value of `codec`'s `key`, parsed; `None` when it is not set.
    pub fn get<T: FromStr>(&self, codec: &str, key: &str) -> Result<Option<T>, SettingsError>
    where
        T::Err: std::fmt::Display,
    {
        let Some(o) = self.own.iter().find(|o| o.codec == codec && o.key == key) else {
            return Ok(None);
        };
        o.value
            .parse()
            .map(Some)
            .map_err(|e: T::Err| SettingsError::BadValue {
                codec: codec.into(),
                key: key.into(),
                value: o.value.clone(),
                reason: e.to_string(),
            })
    }

    /// Checks the own settings of `codec` against its declared `known`
    /// settings: an error for the first whose key is not among them, or
    /// whose value the setting does not take ([`Values::check`]).
    pub fn check(&self, codec: &str, known: &[Setting]) -> Result<(), SettingsError> {
        for o in self.own.iter().filter(|o| o.codec == codec) {
            let Some(setting) = known.iter().find(|k| k.key == o.key) else {
                let keys: Vec<&str> = known.iter().map(|k| k.key).collect();
                return Err(SettingsError::UnknownKey {
                    codec: codec.into(),
                    key: o.key.clone(),
                    known: if keys.is_empty() {
                        "none".into()
                    } else {
                        keys.join(", ")
                    },
                });
            };
            let name = format!("{codec}.{}", o.key);
            setting
                .values
                .check(&name, &o.value)
                .map_err(|reason| SettingsError::BadValue {
                    codec: codec.into(),
                    key: o.key.clone(),
                    value: o.value.clone(),
                    reason,
                })?;
        }
        Ok(())
    }

    /// The common `vertex_bits` for a codec whose default is `default`
    /// (`None`: `f32` vertices): `Some(0)` keeps `f32` vertices.
    pub fn vertex_bits_or(&self, default: Option<u32>) -> Option<u32> {
        match self.vertex_bits {
            None => default,
            Some(0) => None,
            Some(b) => Some(b),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn set_parses_and_replaces() {
        let mut s = Settings::default();
        s.set("racbvh.bits=12").unwrap();
        s.set("racbvh.bits=14").unwrap();
        assert_eq!(s.get::<u32>("racbvh", "bits").unwrap(), Some(14));
        assert_eq!(s.get::<u32>("racbvh", "cluster-nodes").unwrap(), None);
        for bad in [
            "racbvh",
            "racbvh.bits",
            "bits=1",
            ".bits=1",
            "racbvh.=1",
            "racbvh.bits=",
        ] {
            assert!(
                matches!(s.set(bad), Err(SettingsError::Syntax { .. })),
                "{bad}"
            );
        }
    }

    #[test]
    fn bad_values_and_unknown_keys_name_the_setting() {
        let mut s = Settings::default();
        s.set("racbvh.bits=many").unwrap();
        let e = s.get::<u32>("racbvh", "bits").unwrap_err().to_string();
        assert!(e.contains("racbvh.bits=many"), "{e}");
        let cluster_nodes = Setting::power_of_two("cluster-nodes", 256, 16384);
        let e = s.check("racbvh", &[cluster_nodes]).unwrap_err().to_string();
        assert!(
            e.contains("no setting \"bits\"") && e.contains("cluster-nodes"),
            "{e}"
        );
        assert!(s.check("hcc", &[]).is_ok());
        // A declared key with a value its declaration does not take.
        for (value, want) in [
            (
                "100",
                "racbvh.cluster-nodes takes a power of two from 256 to 16384, not 100",
            ),
            ("32768", "not 32768"),
            (
                "-5",
                "-5 is negative: racbvh.cluster-nodes takes a positive number",
            ),
            ("1e3", "\"1e3\" is no whole number"),
            ("99999999999999999999", "not 99999999999999999999"),
        ] {
            let mut s = Settings::default();
            s.set(&format!("racbvh.cluster-nodes={value}")).unwrap();
            let e = s.check("racbvh", &[cluster_nodes]).unwrap_err().to_string();
            assert!(e.contains(want), "{value}: {e}");
        }
        let mut s = Settings::default();
        s.set("racbvh.cluster-nodes=+512").unwrap();
        assert!(s.check("racbvh", &[cluster_nodes]).is_ok());
        s.set("hcc.tree-order=yes").unwrap();
        let e = s
            .check("hcc", &[Setting::flag("tree-order")])
            .unwrap_err()
            .to_string();
        assert!(e.contains("hcc.tree-order takes true or false"), "{e}");
    }

    /// No settings give every codec its defaults.
    #[test]
    fn no_settings_give_the_defaults() {
        let o = crate::codec::AnyOptions::from_settings(
            &Settings::default(),
            crate::codec::CodecKind::ALL,
        )
        .unwrap();
        let d = crate::codec::AnyOptions::default();
        assert_eq!(format!("{o:?}"), format!("{d:?}"));
    }

    /// The common settings reach each codec as its own flags used to.
    #[test]
    fn common_settings_map_onto_each_codec() {
        use crate::codec::{AnyOptions, CodecKind};
        let o = AnyOptions::from_settings(&Settings::new(8, Some(0)), CodecKind::ALL).unwrap();
        assert_eq!(o.racbvh.vertex_bits, None);
        assert_eq!(o.hcc.vertex_bits, None);
        assert_eq!(o.hcc_ooc.vertex_bits, 16, "hcc-ooc always quantizes");
        assert_eq!((o.clbvh.leaf_size, o.clbvh_compact.leaf_size), (8, 8));
        let mut s = Settings::new(1, Some(12));
        s.set("clbvh.leaf-size=2").unwrap();
        s.set("clbvh-compact.multi-leaf=false").unwrap();
        s.set("hcc.tree-order=true").unwrap();
        let o = AnyOptions::from_settings(&s, CodecKind::ALL).unwrap();
        assert_eq!(o.racbvh.vertex_bits, Some(12));
        assert_eq!(o.hcc_ooc.vertex_bits, 12);
        assert_eq!((o.clbvh.leaf_size, o.clbvh.multi_leaf), (2, true));
        assert_eq!(o.clbvh_compact.leaf_size, 6);
        assert!(!o.clbvh_compact.multi_leaf);
        assert!(!o.hcc.vertex_ids && !o.hcc.triangle_ids);
    }

    /// Each codec checks its own values, before any work.
    #[test]
    fn codecs_reject_what_they_cannot_encode() {
        use crate::codec::{AnyOptions, CodecKind};
        for (spec, want) in [
            ("racbvh.cluster-nodes=100", "power of two"),
            ("racbvh.bits=2", "bits"),
            ("clbvh.leaf-size=11", "from 1 to 10, not 11"),
            ("hcc.tree-order=maybe", "hcc.tree-order=maybe"),
            ("plain.anything=1", "plain has no setting"),
            ("zip.level=9", "no codec named \"zip\""),
        ] {
            let mut s = Settings::default();
            s.set(spec).unwrap();
            let e = AnyOptions::from_settings(&s, CodecKind::ALL)
                .unwrap_err()
                .to_string();
            assert!(e.contains(want), "{spec}: {e}");
        }
        // Every codec refuses a key it does not have (the contract checks
        // the keys before the options type reads them).
        for k in CodecKind::ALL {
            let mut s = Settings::default();
            s.set(&format!("{k}.no-such-key=1")).unwrap();
            let e = AnyOptions::from_settings(&s, &[*k])
                .unwrap_err()
                .to_string();
            assert!(e.contains("no-such-key"), "{k}: {e}");
        }
        let e = AnyOptions::from_settings(&Settings::new(1, Some(30)), CodecKind::ALL)
            .unwrap_err()
            .to_string();
        assert!(e.contains("vertex_bits = 30"), "{e}");
        // Only the codecs asked for are checked: 4 bits suit hcc, not RACBVH.
        let s = Settings::new(1, Some(4));
        assert!(AnyOptions::from_settings(&s, &[CodecKind::Hcc]).is_ok());
        assert!(AnyOptions::from_settings(&s, &[CodecKind::Racbvh]).is_err());
        assert!(AnyOptions::from_settings(&s, &[CodecKind::Plain]).is_ok());
    }

    /// Issue 51: a codec's own settings are checked against its
    /// declaration whether the codec is in use or not, and vertex bits
    /// against every codec that quantizes: a plain build (or none at all)
    /// refuses what no codec would take.
    #[test]
    fn settings_of_codecs_not_in_use_are_checked_too() {
        use crate::codec::{AnyOptions, CodecKind};
        for (spec, want) in [
            ("hcc.nosuch=1", "hcc has no setting \"nosuch\""),
            (
                "racbvh.bits=99",
                "racbvh.bits takes a whole number from 8 to 24, not 99",
            ),
            (
                "racbvh.cluster-nodes=100",
                "racbvh.cluster-nodes takes a power of two from 256 to 16384, not 100",
            ),
            (
                "clbvh.leaf-size=0",
                "clbvh.leaf-size takes a whole number from 1 to 10, not 0",
            ),
            ("clbvh-compact.multi-leaf=no", "takes true or false"),
            ("racbvh.tri-delta-threshold=-3", "-3 is negative"),
        ] {
            let mut s = Settings::default();
            s.set(spec).unwrap();
            for kinds in [&[CodecKind::Plain][..], &[]] {
                let e = AnyOptions::from_settings(&s, kinds)
                    .unwrap_err()
                    .to_string();
                assert!(e.contains(want), "{spec} with {kinds:?}: {e}");
            }
        }
        let e = AnyOptions::from_settings(&Settings::new(1, Some(33)), &[CodecKind::Plain])
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("vertex bits 33: no codec quantizes to 33 bits")
                && e.contains("racbvh takes a whole number from 8 to 24")
                && e.contains("hcc takes a whole number from 1 to 24"),
            "{e}"
        );
        for bits in [0, 1, 24] {
            let s = Settings::new(1, Some(bits));
            assert!(
                AnyOptions::from_settings(&s, &[CodecKind::Plain]).is_ok(),
                "{bits}"
            );
        }
    }

    #[test]
    fn vertex_bits_zero_keeps_floats() {
        let mut s = Settings::new(1, Some(0));
        assert_eq!(s.vertex_bits_or(Some(16)), None);
        s.vertex_bits = Some(12);
        assert_eq!(s.vertex_bits_or(None), Some(12));
        s.vertex_bits = None;
        assert_eq!(s.vertex_bits_or(Some(16)), Some(16));
    }
}

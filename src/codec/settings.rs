//! Codec settings as a front end collects them: the settings every codec
//! may use (the canonical tree's leaf size, bits per vertex coordinate)
//! and each codec's own `CODEC.KEY=VALUE` settings, which the codec itself
//! turns into its options ([`Codec::options_from`](super::Codec::options_from)).
//! A front end never names a codec's fields: adding a codec, or a setting
//! to one, touches no front-end file.
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
/// ([`Codec::Options`](super::Codec::Options) requires it): the keys of the
/// codec's own settings, and how those and the common settings the codec
/// uses become its options. The contract refuses a setting under the
/// codec's name with another key before calling `from_settings`
/// ([`Codec::options_from`](super::Codec::options_from)).
pub trait CodecOptions: Sized {
    /// The keys of the codec's own `CODEC.KEY=VALUE` settings (for help
    /// texts, and the only keys the contract lets through).
    const SETTINGS: &'static [&'static str];

    /// The options from `settings`: a bad value, or options the codec
    /// would reject, is an error naming them, before any work.
    fn from_settings(settings: &Settings) -> Result<Self, SettingsError>;
}

/// The options of a codec with nothing to choose (plain): no keys.
impl CodecOptions for () {
    const SETTINGS: &'static [&'static str] = &[];

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

    /// An error for the first own setting of `codec` whose key is not
    /// among `known`.
    pub fn only(&self, codec: &str, known: &[&str]) -> Result<(), SettingsError> {
        match self
            .own
            .iter()
            .find(|o| o.codec == codec && !known.contains(&o.key.as_str()))
        {
            None => Ok(()),
            Some(o) => Err(SettingsError::UnknownKey {
                codec: codec.into(),
                key: o.key.clone(),
                known: if known.is_empty() {
                    "none".into()
                } else {
                    known.join(", ")
                },
            }),
        }
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
        let e = s
            .only("racbvh", &["cluster-nodes"])
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("no setting \"bits\"") && e.contains("cluster-nodes"),
            "{e}"
        );
        assert!(s.only("hcc", &[]).is_ok());
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
            ("clbvh.leaf-size=11", "use 1 to 10"),
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

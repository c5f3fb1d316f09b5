//! The codec registry: the one place that names every codec.
//!
//! - [`CodecKind`]: every codec by name ([`CodecKind::ALL`],
//!   [`CodecKind::name`], parsed with `FromStr`): the names the CLI, the
//!   sims and the JSON reports use.
//! - [`AnyCodec`]: an encoded codec, whichever it is, with what consumers
//!   need of it (sizes, mass, edge flags, verify, save, the decoded mesh,
//!   header fields), encoded by kind ([`AnyCodec::encode`], each codec's options
//!   in [`AnyOptions`]) or opened from any codec file by its magic
//!   ([`AnyCodec::open`]).
//! - [`with_codec!`](crate::with_codec): binds the concrete codec inside an
//!   [`AnyCodec`], so that traversals stay monomorphized per codec.
//!
//! A codec is registered by one entry in the `registry!` invocation below
//! (its variant, type, options field, name and summary) and one arm of
//! [`with_codec!`](crate::with_codec); everything else here is written
//! once over the [`Codec`] contract.

use std::io::Read;
use std::path::{Path, PathBuf};

use super::ByteSize;
use super::clbvh::{ClBvh, ClBvhCompact};
use super::common::MassProps;
use super::common::container::Frame;
use super::contract::{Codec, OpenOptions, StreamedReport};
use super::hcc::HccBvh;
use super::hcc::ooc::HccOocBvh;
use super::plain::PlainBvh;
use super::racbvh::RacBvh;
use super::settings::{CodecOptions, Setting, Settings, SettingsError, Values};
use crate::build::chunked::{ChunkedMesh, Progress};
use crate::build::{BuildOptions, CanonicalBvh};
use crate::contact::EdgeFlags;
use crate::cursor::NodeCursor;
use crate::mesh::Mesh;

/// Declares the registry's types from one entry per codec:
/// `Variant(Type, options_field) = "name", "summary";`.
macro_rules! registry {
    ($( $variant:ident($ty:ty, $field:ident) = $name:literal, $summary:literal; )+) => {
        /// Every codec, by the name the CLI, the sims and the JSON reports
        /// use (see [`CodecKind::name`]).
        #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
        pub enum CodecKind {
            $( #[doc = $summary] $variant, )+
        }

        impl CodecKind {
            /// Every codec, in registry order.
            pub const ALL: &'static [CodecKind] = &[$(CodecKind::$variant),+];

            /// The codec's name, as the CLI's `--codec`, the sims' `--shapes`
            /// and the reports spell it.
            pub const fn name(self) -> &'static str {
                match self {
                    $( CodecKind::$variant => $name, )+
                }
            }

            /// One line on what the codec is (for help texts).
            pub const fn summary(self) -> &'static str {
                match self {
                    $( CodecKind::$variant => $summary, )+
                }
            }

            /// Calls `v` with the codec's type.
            fn visit<V: KindVisitor>(self, v: V) -> V::Output {
                match self {
                    $( CodecKind::$variant => v.visit::<$ty>(), )+
                }
            }
        }

        /// An encoded codec, whichever it is. Match it with
        /// [`with_codec!`](crate::with_codec) to reach the concrete codec.
        // A codec is made once per shape and then shared behind an `Arc`:
        // boxing the larger variants would only add an indirection.
        #[allow(clippy::large_enum_variant)]
        pub enum AnyCodec {
            $( #[doc = $summary] $variant($ty), )+
        }

        /// Each codec's encoding options, for encoding by [`CodecKind`].
        #[derive(Clone, Debug, Default)]
        pub struct AnyOptions {
            $(
                #[doc = concat!("Options of the `", $name, "` codec.")]
                pub $field: <$ty as Codec>::Options,
            )+
        }

        /// A codec's own error, whichever the codec.
        #[derive(Debug, thiserror::Error)]
        pub enum CodecError {
            $(
                #[doc = concat!("From the `", $name, "` codec.")]
                #[error(transparent)]
                $variant(<$ty as Codec>::Error),
            )+
        }

        $(
            impl From<$ty> for AnyCodec {
                fn from(c: $ty) -> Self {
                    AnyCodec::$variant(c)
                }
            }

            impl Registered for $ty {
                fn options(o: &AnyOptions) -> &Self::Options {
                    &o.$field
                }
                fn options_mut(o: &mut AnyOptions) -> &mut Self::Options {
                    &mut o.$field
                }
                fn error(e: Self::Error) -> CodecError {
                    CodecError::$variant(e)
                }
            }
        )+
    };
}

registry! {
    Plain(PlainBvh, plain) = "plain",
        "Uncompressed 32-byte nodes, f32 vertices, u32 indices";
    Racbvh(RacBvh, racbvh) = "racbvh",
        "RACBVH: clusters of consecutive nodes compressed independently, decoded on demand into an LRU cache";
    Clbvh(ClBvh, clbvh) = "clbvh",
        "CLBVH: 8-wide, float inner nodes, 72-byte compressed multi-leaf nodes, pre-gathered triangles";
    ClbvhCompact(ClBvhCompact, clbvh_compact) = "clbvh-compact",
        "CLBVH with compact leaves: de-duplicated vertex indices, 8-bit corner indices";
    Hcc(HccBvh, hcc) = "hcc",
        "i-HCCMesh: low-level trees of < 512 vertices, 4-byte nodes with boxes from vertex indices and reuse masks, tree templates (multi-triangle leaves with --leaf-size > 1, quantized vertices with --vertex-bits)";
    HccOoc(HccOocBvh, hcc_ooc) = "hcc-ooc",
        "o-HCCMesh: the i-HCCMesh dictionary-coded (16-bit grid, tree order by default; no boxes stored), decoded into i-HCCMesh when opened";
}

/// Runs `$body` with `$c` bound to the concrete codec inside an
/// [`AnyCodec`](crate::codec::AnyCodec) (by reference for `&AnyCodec`, by
/// value for an owned one), so that whatever `$body` calls is monomorphized
/// per codec:
///
/// ```
/// # fn demo(codec: &cbvh::codec::AnyCodec) {
/// use cbvh::NodeCursor;
/// let root_box = cbvh::with_codec!(codec, |c| c.root().1);
/// # }
/// ```
#[macro_export]
macro_rules! with_codec {
    ($codec:expr, |$c:ident| $body:expr) => {
        match $codec {
            $crate::codec::AnyCodec::Plain($c) => $body,
            $crate::codec::AnyCodec::Racbvh($c) => $body,
            $crate::codec::AnyCodec::Clbvh($c) => $body,
            $crate::codec::AnyCodec::ClbvhCompact($c) => $body,
            $crate::codec::AnyCodec::Hcc($c) => $body,
            $crate::codec::AnyCodec::HccOoc($c) => $body,
        }
    };
}

/// How a codec sits in the registry (implemented by `registry!`).
trait Registered: Codec + Into<AnyCodec> {
    /// The codec's field of `o`.
    fn options(o: &AnyOptions) -> &Self::Options;
    /// The codec's field of `o`, to change.
    fn options_mut(o: &mut AnyOptions) -> &mut Self::Options;
    /// The codec's error as a [`CodecError`].
    fn error(e: Self::Error) -> CodecError;
}

/// Something to do with a codec's type, chosen by its [`CodecKind`].
trait KindVisitor {
    type Output;
    fn visit<C: Registered>(self) -> Self::Output;
}

/// The error conversion of `c`'s codec (lets `with_codec!` bodies name it).
fn error_of<C: Registered>(_: &C) -> fn(C::Error) -> CodecError {
    C::error
}

/// The kind of `c`'s codec.
fn kind_of<C: Codec>(_: &C) -> CodecKind {
    C::KIND
}

/// A name that is no codec's.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("unknown codec {name:?}; use one of: {}", CodecKind::names(", "))]
pub struct UnknownCodec {
    /// The name given.
    pub name: String,
}

impl CodecKind {
    /// Every codec's name, joined with `separator`.
    pub fn names(separator: &str) -> String {
        CodecKind::ALL
            .iter()
            .map(|k| k.name())
            .collect::<Vec<_>>()
            .join(separator)
    }

    /// The magic the codec's files start with.
    pub fn magic(self) -> [u8; 8] {
        struct Magic;
        impl KindVisitor for Magic {
            type Output = [u8; 8];
            fn visit<C: Registered>(self) -> [u8; 8] {
                C::MAGIC
            }
        }
        self.visit(Magic)
    }

    /// The codec whose magic `head` starts with.
    pub fn of_magic(head: &[u8]) -> Option<CodecKind> {
        CodecKind::ALL
            .iter()
            .copied()
            .find(|k| head.starts_with(&k.magic()))
    }

    /// The codec of the file at `path` if it starts with a codec's magic
    /// (`None` for a mesh or anything else, or a file that cannot be read).
    pub fn of_file(path: &Path) -> Option<CodecKind> {
        let mut head = [0u8; 8];
        let mut f = std::fs::File::open(path).ok()?;
        f.read_exact(&mut head).ok()?;
        CodecKind::of_magic(&head)
    }

    /// The codec's own settings, with the values each takes
    /// ([`CodecOptions::SETTINGS`]).
    pub fn settings(self) -> &'static [Setting] {
        struct Keys;
        impl KindVisitor for Keys {
            type Output = &'static [Setting];
            fn visit<C: Registered>(self) -> &'static [Setting] {
                <C::Options as CodecOptions>::SETTINGS
            }
        }
        self.visit(Keys)
    }

    /// The codec's own setting `key`, if it has one.
    pub fn setting(self, key: &str) -> Option<Setting> {
        self.settings().iter().copied().find(|s| s.key == key)
    }

    /// The bits per vertex coordinate the codec quantizes to, `None` for
    /// a codec that keeps `f32` vertices ([`CodecOptions::VERTEX_BITS`]).
    pub fn vertex_bits(self) -> Option<Values> {
        struct Bits;
        impl KindVisitor for Bits {
            type Output = Option<Values>;
            fn visit<C: Registered>(self) -> Option<Values> {
                <C::Options as CodecOptions>::VERTEX_BITS
            }
        }
        self.visit(Bits)
    }

    /// Checks the common vertex bits against every codec, whether in use
    /// or not: 0 (`f32` vertices) or bits that some codec quantizes to
    /// ([`CodecKind::vertex_bits`]); an error lists what the codecs take.
    /// Whether the codecs in use take them is theirs to check
    /// ([`AnyOptions::from_settings`]).
    pub fn check_vertex_bits(bits: u32) -> Result<(), SettingsError> {
        let quantizing = || {
            CodecKind::ALL
                .iter()
                .filter_map(|k| k.vertex_bits().map(|v| (*k, v)))
        };
        if bits == 0 || quantizing().any(|(_, v)| v.allows(u64::from(bits))) {
            return Ok(());
        }
        let codecs: Vec<String> = quantizing()
            .map(|(k, v)| format!("{k} takes {v}"))
            .collect();
        Err(SettingsError::VertexBits {
            bits,
            codecs: codecs.join(", "),
        })
    }

    /// The frame of the codec's files ([`Codec::FRAME`]): where their
    /// section table lies, their sections' names.
    pub fn frame(self) -> Frame {
        struct FrameOf;
        impl KindVisitor for FrameOf {
            type Output = Frame;
            fn visit<C: Registered>(self) -> Frame {
                C::FRAME
            }
        }
        self.visit(FrameOf)
    }

    /// Whether the codec decodes into a cache under a byte budget
    /// (see [`Codec::cache_budget`]).
    pub fn has_cache(self) -> bool {
        struct HasCache;
        impl KindVisitor for HasCache {
            type Output = bool;
            fn visit<C: Registered>(self) -> bool {
                C::cache_budget(&mut C::Options::default()).is_some()
            }
        }
        self.visit(HasCache)
    }

    /// Whether the codec builds out of core (see
    /// [`Codec::BUILDS_OUT_OF_CORE`]).
    pub fn builds_out_of_core(self) -> bool {
        struct OutOfCore;
        impl KindVisitor for OutOfCore {
            type Output = bool;
            fn visit<C: Registered>(self) -> bool {
                C::BUILDS_OUT_OF_CORE
            }
        }
        self.visit(OutOfCore)
    }

    /// Whether the codec's encoding depends on its cache budget (see
    /// [`Codec::ENCODES_FOR_CACHE_BUDGET`]).
    pub fn encodes_for_cache_budget(self) -> bool {
        struct EncodesForBudget;
        impl KindVisitor for EncodesForBudget {
            type Output = bool;
            fn visit<C: Registered>(self) -> bool {
                C::ENCODES_FOR_CACHE_BUDGET
            }
        }
        self.visit(EncodesForBudget)
    }
}

impl std::fmt::Display for CodecKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for CodecKind {
    type Err = UnknownCodec;
    fn from_str(s: &str) -> Result<Self, UnknownCodec> {
        CodecKind::ALL
            .iter()
            .copied()
            .find(|k| k.name() == s.trim())
            .ok_or_else(|| UnknownCodec {
                name: s.to_string(),
            })
    }
}

impl AnyOptions {
    /// The options of the codecs `kinds` from a front end's settings, each
    /// made and checked by its codec ([`Codec::options_from`]); the other
    /// codecs keep their defaults (a `--vertex-bits 4` for hcc is no error
    /// because RACBVH could not take it). Every setting is checked whatever
    /// codecs are in use: one naming no codec, a key its codec does not
    /// have or a value its codec's declaration does not take
    /// ([`Settings::check`]), and vertex bits no codec quantizes to
    /// ([`CodecKind::check_vertex_bits`]), are errors; the codecs in use
    /// are checked first, with their own messages.
    pub fn from_settings(settings: &Settings, kinds: &[CodecKind]) -> Result<Self, SettingsError> {
        if let Some((codec, key)) = settings
            .named_codecs()
            .find(|(c, _)| c.parse::<CodecKind>().is_err())
        {
            return Err(SettingsError::UnknownCodec {
                codec: codec.into(),
                key: key.into(),
                known: CodecKind::names(", "),
            });
        }
        for k in kinds.iter().chain(CodecKind::ALL) {
            settings.check(k.name(), k.settings())?;
        }
        struct Make<'a>(&'a mut AnyOptions, &'a Settings);
        impl KindVisitor for Make<'_> {
            type Output = Result<(), SettingsError>;
            fn visit<C: Registered>(self) -> Result<(), SettingsError> {
                *C::options_mut(self.0) = C::options_from(self.1)?;
                Ok(())
            }
        }
        let mut options = AnyOptions::default();
        for k in kinds {
            k.visit(Make(&mut options, settings))?;
        }
        if let Some(bits) = settings.vertex_bits {
            CodecKind::check_vertex_bits(bits)?;
        }
        Ok(options)
    }

    /// Codec `kind`'s options, as their `Debug` form (for reports: every
    /// field, with no front end naming one).
    pub fn describe(&self, kind: CodecKind) -> String {
        struct Describe<'a>(&'a AnyOptions);
        impl KindVisitor for Describe<'_> {
            type Output = String;
            fn visit<C: Registered>(self) -> String {
                format!("{:?}", C::options(self.0))
            }
        }
        kind.visit(Describe(self))
    }

    /// The out-of-core build of codec `kind` with these options
    /// ([`Codec::encode_streamed`]): `input` built with `build_options`
    /// and written to `out`. `None` for a codec that builds only in
    /// memory ([`CodecKind::builds_out_of_core`]).
    pub fn encode_streamed(
        &self,
        kind: CodecKind,
        input: &ChunkedMesh,
        build_options: &BuildOptions,
        out: &Path,
        progress: Progress<'_>,
    ) -> Option<Result<StreamedReport, CodecError>> {
        struct Stream<'a> {
            options: &'a AnyOptions,
            input: &'a ChunkedMesh,
            build_options: &'a BuildOptions,
            out: &'a Path,
            progress: Progress<'a>,
        }
        impl KindVisitor for Stream<'_> {
            type Output = Option<Result<StreamedReport, CodecError>>;
            fn visit<C: Registered>(self) -> Self::Output {
                let made = C::encode_streamed(
                    self.input,
                    self.build_options,
                    C::options(self.options),
                    self.out,
                    self.progress,
                )?;
                Some(made.map_err(C::error))
            }
        }
        kind.visit(Stream {
            options: self,
            input,
            build_options,
            out,
            progress,
        })
    }

    /// These options with every cached codec's cache budget set to `bytes`
    /// (`usize::MAX`: a cache that holds the whole decoded tree).
    pub fn with_cache_budget(mut self, bytes: usize) -> Self {
        struct SetBudget<'a>(&'a mut AnyOptions, usize);
        impl KindVisitor for SetBudget<'_> {
            type Output = ();
            fn visit<C: Registered>(self) {
                if let Some(b) = C::cache_budget(C::options_mut(self.0)) {
                    *b = self.1;
                    C::fit_cache_budget(C::options_mut(self.0));
                }
            }
        }
        for k in CodecKind::ALL {
            k.visit(SetBudget(&mut self, bytes));
        }
        self
    }
}

/// What can go wrong opening a codec file.
#[derive(Debug, thiserror::Error)]
pub enum CodecFileError {
    /// The file could not be read.
    #[error(transparent)]
    Io(#[from] crate::files::IoError),
    /// The file starts with no codec magic.
    #[error(
        "{path}: not a cbvh codec file (no known magic); give a mesh (.off, .ply, .obj, .stl) \
         or a file written by `cbvh build ... -o FILE`"
    )]
    NotACodecFile {
        /// The file.
        path: PathBuf,
    },
    /// The file is damaged or forged (found when opening it).
    #[error("{path}: {source}")]
    Open {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        #[source]
        source: CodecError,
    },
    /// `verify` found the file's contents inconsistent.
    #[error("{path}: verify failed: {source}; the file is damaged: rebuild it with `cbvh build`")]
    Verify {
        /// The file.
        path: PathBuf,
        /// What `verify` found.
        #[source]
        source: CodecError,
    },
}

impl std::fmt::Debug for AnyCodec {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl AnyCodec {
    /// Encodes `bvh` (built over `mesh`) with the codec `kind` and its
    /// options in `options`.
    pub fn encode(
        kind: CodecKind,
        bvh: &CanonicalBvh,
        mesh: &Mesh,
        options: &AnyOptions,
    ) -> Result<AnyCodec, CodecError> {
        AnyCodec::encode_with_progress(kind, bvh, mesh, options, &|_, _| {})
    }

    /// [`AnyCodec::encode`], calling `progress(done, total)` as the codec
    /// reports progress (see [`Codec::encode_with_progress`]).
    pub fn encode_with_progress(
        kind: CodecKind,
        bvh: &CanonicalBvh,
        mesh: &Mesh,
        options: &AnyOptions,
        progress: &(dyn Fn(u64, u64) + Sync),
    ) -> Result<AnyCodec, CodecError> {
        struct Encode<'a> {
            bvh: &'a CanonicalBvh,
            mesh: &'a Mesh,
            options: &'a AnyOptions,
            progress: &'a (dyn Fn(u64, u64) + Sync),
        }
        impl KindVisitor for Encode<'_> {
            type Output = Result<AnyCodec, CodecError>;
            fn visit<C: Registered>(self) -> Self::Output {
                let o = C::options(self.options);
                C::encode_with_progress(self.bvh, self.mesh, o, self.progress)
                    .map(Into::into)
                    .map_err(C::error)
            }
        }
        kind.visit(Encode {
            bvh,
            mesh,
            options,
            progress,
        })
    }

    /// Opens the codec file at `path`, whatever its codec (chosen by its
    /// magic, not its extension), and verifies it unless `options` say not
    /// to. How a file is read is the codec's choice: RACBVH files are
    /// memory-mapped (clusters decoded on demand), plain files read into
    /// memory.
    pub fn open(path: &Path, options: &OpenOptions) -> Result<AnyCodec, CodecFileError> {
        struct Open<'a>(&'a Path, &'a OpenOptions);
        impl KindVisitor for Open<'_> {
            type Output = Result<AnyCodec, CodecError>;
            fn visit<C: Registered>(self) -> Self::Output {
                C::open(self.0, self.1).map(Into::into).map_err(C::error)
            }
        }
        let p = || path.to_path_buf();
        let Some(kind) = CodecKind::of_file(path) else {
            // Distinguish an unreadable file from a foreign one.
            std::fs::File::open(path).map_err(crate::files::IoError::at(path))?;
            return Err(CodecFileError::NotACodecFile { path: p() });
        };
        let codec = kind
            .visit(Open(path, options))
            .map_err(|source| CodecFileError::Open { path: p(), source })?;
        if options.verify {
            codec
                .verify()
                .map_err(|source| CodecFileError::Verify { path: p(), source })?;
        }
        Ok(codec)
    }

    /// Reads the bytes of a file of the codec `kind` (see
    /// [`Codec::from_bytes`]), and verifies them unless `options` say not
    /// to.
    pub fn from_bytes(
        kind: CodecKind,
        bytes: &[u8],
        options: &OpenOptions,
    ) -> Result<AnyCodec, CodecError> {
        struct FromBytes<'a>(&'a [u8], &'a OpenOptions);
        impl KindVisitor for FromBytes<'_> {
            type Output = Result<AnyCodec, CodecError>;
            fn visit<C: Registered>(self) -> Self::Output {
                C::from_bytes(self.0, self.1)
                    .map(Into::into)
                    .map_err(C::error)
            }
        }
        let codec = kind.visit(FromBytes(bytes, options))?;
        if options.verify {
            codec.verify()?;
        }
        Ok(codec)
    }

    /// The codec's file as bytes (what [`AnyCodec::save`] writes).
    pub fn to_bytes(&self) -> Vec<u8> {
        crate::with_codec!(self, |c| Codec::to_bytes(c))
    }

    /// The codec's registry entry.
    pub fn kind(&self) -> CodecKind {
        crate::with_codec!(self, |c| kind_of(c))
    }

    /// The codec's name, as used by the sims' `--shapes` and reports.
    pub fn name(&self) -> &'static str {
        self.kind().name()
    }

    /// The root's box: the bounds of every triangle, as the codec
    /// decodes them.
    pub fn root_box(&self) -> crate::geom::Aabb {
        crate::with_codec!(self, |c| crate::cursor::NodeCursor::root(c).1)
    }

    /// Number of triangles.
    pub fn triangle_count(&self) -> usize {
        crate::with_codec!(self, |c| c.triangle_count())
    }

    /// The vertex indices of triangle `id` (see [`Codec::triangle_vertices`]).
    pub fn triangle_vertices(&self, id: u32) -> [u32; 3] {
        crate::with_codec!(self, |c| c.triangle_vertices(id))
    }

    /// Mass properties at density 1, as stored with the codec.
    pub fn mass(&self) -> MassProps {
        crate::with_codec!(self, |c| Codec::mass(c))
    }

    /// The active-edge flags of the triangles by id, as the codec stores
    /// them (see [`Codec::edge_flags`]).
    pub fn edge_flags(&self) -> &EdgeFlags {
        crate::with_codec!(self, |c| Codec::edge_flags(c))
    }

    /// The decode cache's counters (see [`Codec::cache_stats`]).
    pub fn cache_stats(&self) -> Option<super::CacheStats> {
        crate::with_codec!(self, |c| Codec::cache_stats(c))
    }

    /// Proves everything a query relies on (see [`Codec::verify`]).
    pub fn verify(&self) -> Result<(), CodecError> {
        crate::with_codec!(self, |c| Codec::verify(c).map_err(error_of(c)))
    }

    /// Writes the codec's self-contained file (atomically).
    pub fn save(&self, path: &Path) -> Result<(), CodecError> {
        crate::with_codec!(self, |c| Codec::save(c, path).map_err(error_of(c)))
    }

    /// The mesh as stored (quantized vertices decoded), triangle `k` being
    /// the one the cursor reports as id `k`: the input's triangle `k`.
    pub fn decoded_mesh(&self) -> Mesh {
        crate::with_codec!(self, |c| Codec::decoded_mesh(c))
    }

    /// The codec's header fields, for `cbvh info`: its name, its own
    /// fields, the triangle count and the mass.
    pub fn header_fields(&self) -> Vec<(&'static str, String)> {
        let mut out = vec![("codec", self.name().to_string())];
        out.extend(crate::with_codec!(self, |c| Codec::header_fields(c)));
        out.push(("triangles", self.triangle_count().to_string()));
        let m = self.mass();
        out.push((
            "mass (density 1)",
            format!("{} at ({}, {}, {})", m.mass, m.com[0], m.com[1], m.com[2]),
        ));
        out
    }

    /// The figures `cbvh build` reports (see [`Codec::build_fields`]).
    #[cfg(feature = "serde")]
    pub fn build_fields(&self) -> Vec<(&'static str, serde_json::Value)> {
        crate::with_codec!(self, |c| c.build_fields())
    }

    /// For a codec with a cache, the same codec with a cache of
    /// `budget(bytes of the whole decoded tree)` (see
    /// [`Codec::with_cache_budget_of`]); `None` for a codec without one.
    pub fn with_cache_budget_of(
        &self,
        budget: &dyn Fn(usize) -> usize,
    ) -> Option<Result<AnyCodec, CodecError>> {
        crate::with_codec!(self, |c| c
            .with_cache_budget_of(budget)
            .map(|r| r.map(Into::into).map_err(error_of(c))))
    }
}

impl ByteSize for AnyCodec {
    fn bytes_by_part(&self) -> Vec<(&'static str, usize)> {
        crate::with_codec!(self, |c| c.bytes_by_part())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_parse_back_and_unknown_names_list_the_codecs() {
        for &k in CodecKind::ALL {
            assert_eq!(k.name().parse::<CodecKind>(), Ok(k));
            assert_eq!(k.to_string(), k.name());
            assert_eq!(CodecKind::of_magic(&k.magic()), Some(k));
        }
        let e = "zip".parse::<CodecKind>().unwrap_err();
        assert_eq!(
            e.to_string(),
            format!(
                "unknown codec \"zip\"; use one of: {}",
                CodecKind::names(", ")
            )
        );
    }

    #[test]
    fn every_kind_has_an_any_codec_variant() {
        let mesh = Mesh::new(
            vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
            vec![[0, 1, 2]],
        );
        let bvh = crate::build::build_default(&mesh).unwrap();
        for &k in CodecKind::ALL {
            let c = AnyCodec::encode(k, &bvh, &mesh, &AnyOptions::default()).unwrap();
            assert_eq!(c.kind(), k);
            assert_eq!(c.triangle_count(), 1);
            assert_eq!(c.triangle_vertices(0), [0, 1, 2]);
            c.verify().unwrap();
        }
    }
}

//! A minimal logger for the binaries: `log` records at `Warn` and above
//! (or what `CBVH_LOG` names: `error`, `warn`, `info`, `debug`, `trace`)
//! printed to stderr as `warning: …`.
//!
//! The library itself only logs through the `log` crate; an application
//! embedding cbvh installs whatever logger it uses.

use log::{Level, LevelFilter, Log, Metadata, Record};

struct Stderr;

impl Log for Stderr {
    fn enabled(&self, m: &Metadata<'_>) -> bool {
        m.level() <= log::max_level()
    }

    fn log(&self, r: &Record<'_>) {
        if self.enabled(r.metadata()) {
            let tag = match r.level() {
                Level::Error => "error",
                Level::Warn => "warning",
                Level::Info => "info",
                Level::Debug => "debug",
                Level::Trace => "trace",
            };
            eprintln!("{tag}: {}", r.args());
        }
    }

    fn flush(&self) {}
}

/// Installs the stderr logger (once; later calls do nothing).
pub fn init_stderr() {
    let level = match std::env::var("CBVH_LOG").as_deref() {
        Ok("error") => LevelFilter::Error,
        Ok("info") => LevelFilter::Info,
        Ok("debug") => LevelFilter::Debug,
        Ok("trace") => LevelFilter::Trace,
        Ok("off") => LevelFilter::Off,
        _ => LevelFilter::Warn,
    };
    if log::set_logger(&Stderr).is_ok() {
        log::set_max_level(level);
    }
}

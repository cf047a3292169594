//! Rebuild when the embedded front end or exercises change: rust-embed includes the files of
//! `web/`, `static/` and `exercises/` at compile time, but cargo only notices new or removed files if told to watch
//! the folders.
//!
//! Also stamps the simulator's version for replays: `SEAARMS_SIM_HASH` is an FNV-1a hash of
//! every source that decides what a recorded attempt's inputs make the simulation do (the
//! core, the robot files, the exercises, the live state, its commands and its step, the
//! replay code; not the recorder, the frames or the edges). An attempt recorded
//! under another hash is reported as not replayable rather than replayed wrongly.
use std::path::Path;

const SIM_SOURCES: &[&str] = &[
    "server/core/src",
    "server/core/robots",
    "exercises",
    "server/src/sessions/mod.rs",
    "server/src/sessions/command",
    "server/src/sessions/physics.rs",
    "server/src/replay",
    "server/src/exercises.rs",
    "server/src/catalogue.rs",
];

fn main() {
    println!("cargo:rerun-if-changed=web");
    println!("cargo:rerun-if-changed=static");
    println!("cargo:rerun-if-changed=exercises");
    // `sqlx::migrate!()` embeds `migrations/` at compile time.
    println!("cargo:rerun-if-changed=migrations");
    let mut files = Vec::new();
    for s in SIM_SOURCES {
        println!("cargo:rerun-if-changed={s}");
        collect(Path::new(s), &mut files);
    }
    files.sort();
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for f in &files {
        let bytes = std::fs::read(f).unwrap_or_default();
        for b in f.to_string_lossy().bytes().chain([0]).chain(bytes) {
            h ^= u64::from(b);
            h = h.wrapping_mul(0x0000_0100_0000_01b3);
        }
    }
    println!("cargo:rustc-env=SEAARMS_SIM_HASH={h:016x}");
}

fn collect(path: &Path, out: &mut Vec<std::path::PathBuf>) {
    if path.is_dir() {
        if let Ok(entries) = std::fs::read_dir(path) {
            for e in entries.flatten() {
                collect(&e.path(), out);
            }
        }
    } else if path.is_file() {
        out.push(path.to_path_buf());
    }
}

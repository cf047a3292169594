//! Rebuild when the embedded front end or exercises change: rust-embed includes the files of
//! `web/`, `static/` and `exercises/` at compile time, but cargo only notices new or removed files if told to watch
//! the folders.
fn main() {
    println!("cargo:rerun-if-changed=web");
    println!("cargo:rerun-if-changed=static");
    println!("cargo:rerun-if-changed=exercises");
}

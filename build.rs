//! Rebuild when the embedded front end changes: rust-embed includes the files of `web/` and
//! `static/` at compile time, but cargo only notices new or removed files if told to watch
//! the folders.
fn main() {
    println!("cargo:rerun-if-changed=web");
    println!("cargo:rerun-if-changed=static");
}

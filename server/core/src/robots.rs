//! Built-in robot models, stored as JSON files in the inline-model schema
//! ([`crate::model::ModelSpec`]) and embedded in the binary. Each file cites its source and
//! says how values the documents do not print were chosen. The core holds only the text;
//! callers parse it (the core has no JSON parser, by design).

/// (name, JSON text) of every built-in model.
pub const BUILTIN: &[(&str, &str)] = &[
    ("magnum", include_str!("../robots/magnum.json")),
    ("orion", include_str!("../robots/orion.json")),
    ("rx90", include_str!("../robots/rx90.json")),
    ("puma560", include_str!("../robots/puma560.json")),
    ("pa10", include_str!("../robots/pa10.json")),
    ("planar2r", include_str!("../robots/planar2r.json")),
];

/// JSON text of a built-in model, if `name` is one.
pub fn builtin_text(name: &str) -> Option<&'static str> {
    BUILTIN.iter().find(|(n, _)| *n == name).map(|(_, t)| *t)
}

//! seaarms server.

pub mod analysis_ext;

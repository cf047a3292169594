//! seaarms server.

pub mod scenarios;

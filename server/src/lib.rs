//! seaarms server.

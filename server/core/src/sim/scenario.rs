//! Scripted scenarios (filled below).

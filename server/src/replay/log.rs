//! An attempt's input log: every input, setting, action and fault applied to the live state,
//! stamped with the step it was applied before, as one deflate stream.
//!
//! * **What is logged** is what changes the simulation: stick input (quantized to
//!   [`INPUT_QUANTUM`] at the edge, so the logged integers give back the applied values
//!   bit for bit), settings, release, diagnosis, faults, the instructor's water current, and instructor
//!   interventions
//!   (they count in an exercise's score). Pause and resume are not: a paused session takes no
//!   steps, so the step stamps already account for them.
//! * **On disk** each entry is a JSON line. Stick input, the bulk of it, is written as
//!   `[dk, i, d, i, d, …]`: steps since the previous entry, then the index and change of each
//!   of the 20 values that changed (in quanta); other entries are objects with `dk`. The lines
//!   go through one deflate stream per attempt, sync-flushed into a piece about every second:
//!   the pieces so far always decode (a killed server loses at most the last second), and
//!   the compression context spans the whole attempt, which keeps the record to a few
//!   kilobytes per minute ([`crate::replay`] tests measure it).

use std::io::{Read, Write};

use flate2::Compression;
use flate2::read::DeflateDecoder;
use flate2::write::DeflateEncoder;
use serde::{Deserialize, Serialize};

use crate::protocol::{ControlMethod, ControlMode};

/// Format of the log (stamped in every attempt's `init`).
pub const FORMAT: u32 = 1;
/// Stick values are applied in steps of this size (a thousandth of full stick: finer than a
/// proportional valve's hysteresis, coarser than a gamepad's noise).
pub const INPUT_QUANTUM: f64 = 1e-3;
/// Values per stick input: left axes 0–5 and grip, right axes 0–5 and grip, object twist 0–5.
pub const INPUT_VALUES: usize = 20;

/// A stick value in quanta (`v` is finite and in [−1, 1] after the edge's checks).
pub fn quantize(v: f64) -> i32 {
    (v.clamp(-1.0, 1.0) / INPUT_QUANTUM).round() as i32
}

/// The value of `n` quanta.
pub fn dequantize(n: i32) -> f64 {
    f64::from(n) * INPUT_QUANTUM
}

/// One logged entry: what was applied, stamped with the simulation's step count `k` when it
/// was applied (it acts from the next step on). On the API: `{"k": …, "c": kind, …}`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Entry {
    /// Step.
    pub k: u64,
    /// What.
    #[serde(flatten)]
    pub what: Applied,
}

/// What an entry applied.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "c", rename_all = "snake_case")]
pub enum Applied {
    /// Stick input, in quanta.
    Input {
        /// The 20 values ([`INPUT_VALUES`]).
        v: Vec<i32>,
    },
    /// Settings change.
    Settings {
        /// Joint or Cartesian.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        mode: Option<ControlMode>,
        /// Open or closed loop.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        method: Option<ControlMethod>,
        /// Arm speed.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        speed: Option<f64>,
    },
    /// Both jaws driven open.
    Release,
    /// A fault-drill answer.
    Diagnose {
        /// The answer.
        answer: String,
    },
    /// A fault injected.
    Fault {
        /// The fault (arm, kind, joint, size).
        fault: FaultEntry,
    },
    /// Every fault removed.
    ClearFaults,
    /// The water's current set by the instructor.
    Current {
        /// Speed (m/s).
        speed_m_s: f64,
        /// Direction it flows towards (degrees from +x towards +y).
        heading_deg: f64,
    },
    /// An instructor's command counted as an intervention.
    Intervention,
}

/// A fault as logged (the wire's fields, see `POST /api/sessions/{id}/actions`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FaultEntry {
    /// 0 left, 1 right.
    pub arm: usize,
    /// Wire name of the kind (`supply_drop`, `stuck_valve`, `leak`, `air`).
    pub kind: String,
    /// Actuator, for per-joint kinds.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub joint: Option<usize>,
    /// Size (Pa, spool position, m³/(s·Pa) or bulk-modulus scale).
    pub value: f64,
}

/// Writes one attempt's log.
pub struct Writer {
    enc: DeflateEncoder<Vec<u8>>,
    last_step: u64,
    last_input: Option<Vec<i32>>,
    /// Uncompressed bytes written.
    raw_bytes: u64,
}

impl Default for Writer {
    fn default() -> Self {
        Writer::new()
    }
}

impl Writer {
    /// An empty log.
    pub fn new() -> Writer {
        Writer {
            enc: DeflateEncoder::new(Vec::new(), Compression::default()),
            last_step: 0,
            last_input: None,
            raw_bytes: 0,
        }
    }

    /// Appends an entry. An input equal to the last one is skipped (applying it again
    /// changes nothing); any other entry forgets the last input, since a mode change
    /// clears the applied sticks and the same input then matters again.
    pub fn push(&mut self, entry: &Entry) {
        let dk = entry.k.saturating_sub(self.last_step);
        let line = match &entry.what {
            Applied::Input { v } => {
                if self.last_input.as_ref() == Some(v) {
                    return;
                }
                let prev = self.last_input.take().unwrap_or_else(|| vec![0; v.len()]);
                let mut parts = vec![dk as i64];
                for (i, (a, b)) in v.iter().zip(&prev).enumerate() {
                    if a != b {
                        parts.push(i as i64);
                        parts.push(i64::from(*a) - i64::from(*b));
                    }
                }
                self.last_input = Some(v.clone());
                serde_json::to_string(&parts)
            }
            other => {
                self.last_input = None;
                serde_json::to_value(other).and_then(|mut v| {
                    v["dk"] = dk.into();
                    serde_json::to_string(&v)
                })
            }
        };
        let Ok(mut line) = line else {
            return;
        };
        line.push('\n');
        self.last_step = entry.k;
        self.raw_bytes += line.len() as u64;
        // Writing into a Vec does not fail.
        let _ = self.enc.write_all(line.as_bytes());
    }

    /// The compressed bytes since the last piece, sync-flushed so everything pushed so far
    /// decodes.
    pub fn take_piece(&mut self) -> Vec<u8> {
        let _ = self.enc.flush();
        std::mem::take(self.enc.get_mut())
    }

    /// The last piece: the stream's end.
    pub fn finish(&mut self) -> Vec<u8> {
        let _ = self.enc.try_finish();
        std::mem::take(self.enc.get_mut())
    }

    /// Uncompressed bytes so far.
    pub fn raw_bytes(&self) -> u64 {
        self.raw_bytes
    }
}

/// Why a log cannot be read.
#[derive(Debug, thiserror::Error)]
#[error("input log line {line}: {message}")]
pub struct DecodeError {
    line: usize,
    message: String,
}

/// Decodes a log (its pieces concatenated). A stream cut after a piece (a killed server)
/// decodes up to that piece.
pub fn decode(bytes: &[u8]) -> Result<Vec<Entry>, DecodeError> {
    let mut text = Vec::new();
    let mut dec = DeflateDecoder::new(bytes);
    let mut buf = [0u8; 16 * 1024];
    loop {
        match dec.read(&mut buf) {
            Ok(0) | Err(_) => break,
            Ok(n) => text.extend_from_slice(&buf[..n]),
        }
    }
    let whole = crate::csv_out::complete_lines(&text);
    let mut entries = Vec::new();
    let mut step = 0u64;
    let mut last: Option<Vec<i32>> = None;
    for (i, line) in whole.split(|b| *b == b'\n').enumerate() {
        if line.is_empty() {
            continue;
        }
        let err = |message: String| DecodeError {
            line: i + 1,
            message,
        };
        if line.first() == Some(&b'[') {
            let parts: Vec<i64> = serde_json::from_slice(line).map_err(|e| err(e.to_string()))?;
            let (&dk, changes) = parts
                .split_first()
                .ok_or_else(|| err("empty input".into()))?;
            step += u64::try_from(dk).map_err(|_| err("negative step".into()))?;
            let mut v = last.take().unwrap_or_else(|| vec![0; INPUT_VALUES]);
            for pair in changes.chunks(2) {
                let [i, d] = pair else {
                    return Err(err("odd input change list".into()));
                };
                let slot = usize::try_from(*i)
                    .ok()
                    .and_then(|i| v.get_mut(i))
                    .ok_or_else(|| err(format!("input index {i}")))?;
                *slot = i32::try_from(i64::from(*slot) + d)
                    .map_err(|_| err("input value out of range".into()))?;
            }
            last = Some(v.clone());
            entries.push(Entry {
                k: step,
                what: Applied::Input { v },
            });
        } else {
            let mut value: serde_json::Value =
                serde_json::from_slice(line).map_err(|e| err(e.to_string()))?;
            let dk = value
                .as_object_mut()
                .and_then(|o| o.remove("dk"))
                .and_then(|d| d.as_u64())
                .ok_or_else(|| err("no step (dk)".into()))?;
            step += dk;
            let what: Applied = serde_json::from_value(value).map_err(|e| err(e.to_string()))?;
            last = None;
            entries.push(Entry { k: step, what });
        }
    }
    Ok(entries)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn entries_round_trip_through_pieces_and_a_cut_stream_keeps_whole_pieces() {
        let mut w = Writer::new();
        let mut all = Vec::new();
        let mut pieces = Vec::new();
        for k in 0..500u64 {
            let mut v = vec![0; INPUT_VALUES];
            v[2] = quantize((k as f64 * 0.01).sin());
            v[19] = -(k as i32 % 7);
            let e = Entry {
                k: k * 20,
                what: Applied::Input { v },
            };
            w.push(&e);
            all.push(e);
            if k % 100 == 50 {
                let e = Entry {
                    k: k * 20,
                    what: Applied::Fault {
                        fault: FaultEntry {
                            arm: 1,
                            kind: "leak".into(),
                            joint: Some(3),
                            value: 1e-11,
                        },
                    },
                };
                w.push(&e);
                all.push(e);
            }
            if k % 50 == 49 {
                pieces.push(w.take_piece());
            }
        }
        pieces.push(w.finish());
        assert_eq!(decode(&pieces.concat()).unwrap(), all);
        // Cut after the third piece (a killed server): the entries of the first three pieces.
        let cut = decode(&pieces[..3].concat()).unwrap();
        assert_eq!(cut.as_slice(), &all[..cut.len()]);
        assert!(cut.len() >= 150, "{}", cut.len());
    }

    #[test]
    fn the_quantum_gives_back_the_applied_value_exactly() {
        for x in [-1.0, -0.3337, 0.0, 0.0005, 0.12345, 1.0] {
            let n = quantize(x);
            assert_eq!(
                dequantize(n).to_bits(),
                dequantize(quantize(dequantize(n))).to_bits()
            );
            assert!((dequantize(n) - x).abs() <= INPUT_QUANTUM / 2.0 + 1e-15);
        }
    }
}

#[cfg(test)]
mod size {
    use super::*;

    /// A trainee-like minute: four sticks moving at once, each a slow sine with a
    /// ±3-quantum jitter, at the page's 50 Hz: every message changes four values.
    #[test]
    fn a_busy_minute_of_four_moving_sticks_stays_under_50_kb() {
        let mut w = Writer::new();
        let mut seed = 1u64;
        for m in 0..3000u64 {
            let mut v = vec![0; INPUT_VALUES];
            for (n, slot) in [0usize, 1, 2, 13].into_iter().enumerate() {
                seed = seed
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                let jitter = ((seed >> 33) % 7) as i32 - 3;
                let phase = m as f64 * 0.02 * (0.3 + 0.2 * n as f64);
                v[slot] = quantize(0.8 * phase.sin()) + jitter;
            }
            w.push(&Entry {
                k: m * 20,
                what: Applied::Input { v },
            });
        }
        let bytes = w.finish().len();
        println!("busy minute: {} B raw, {bytes} B compressed", w.raw_bytes());
        assert!(bytes < 50_000, "{bytes}");
    }
}

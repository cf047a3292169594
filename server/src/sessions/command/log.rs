//! An attempt's record: its initial conditions ([`Init`]) and its input log, every
//! [`Command`] applied to the live state that changes the simulation, stamped with the step
//! it was applied before, as one deflate stream. [`crate::replay`] re-simulates it.
//!
//! * **What is logged** is what changes the simulation: the [`Command`]s themselves, in
//!   their log form (each command's file, [`super`]): stick input (quantized to
//!   [`INPUT_QUANTUM`] when applied, so the logged integers give back the applied values bit
//!   for bit), settings, release, diagnosis, faults, the instructor's water current; and
//!   instructor interventions (they count in an exercise's score). Pause and resume are not:
//!   a paused session takes no steps, so the step stamps already account for them.
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
use seaarms_core::hydraulics::Faults;
use seaarms_core::sim::water::Current;
use serde::{Deserialize, Serialize};

use super::Command;
use super::fault::log_form::FaultEntry;
use crate::protocol::Settings;

/// Format of the log (stamped in every attempt's `init`).
pub const FORMAT: u32 = 1;

/// The simulator's version stamp: the crate version and a hash of every source that decides
/// what the logged inputs do (see `build.rs`).
pub const SIM_VERSION: &str = concat!(env!("CARGO_PKG_VERSION"), "+", env!("SEAARMS_SIM_HASH"));

/// An attempt's initial conditions: with the log, all replay needs.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Init {
    /// Log format ([`FORMAT`]).
    pub format: u32,
    /// Scenario name or exercise id.
    pub scenario: String,
    /// Settings at the start.
    pub settings: Settings,
    /// Instructor faults active at the start (shown in frames).
    pub faults: Vec<FaultEntry>,
    /// The simulation's fault parameters per arm at the start (left, right), exactly.
    pub sim_faults: [Faults; 2],
    /// Seed of the attempt's random draws.
    pub seed: u64,
    /// The water's current at the start (a subsea scenario with a current set; absent:
    /// still water or air).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub current: Option<Current>,
    /// The reference operators' benchmark pass lines the attempt is judged by (an exercise
    /// whose pass marks are `benchmark`, once its benchmark applies; absent: the file's marks).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub pass_lines: Option<seaarms_core::exercise::proficiency::PassLines>,
    /// A practice attempt taken over from another attempt's replay ("take over from here",
    /// issue 30 item 5): it starts from that attempt's replayed state at a step, not from the
    /// fields above (which are the source's initial conditions, copied). Absent: an attempt
    /// started from its scenario's reset state.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub from: Option<Source>,
}

/// Where a practice attempt's state comes from: the attempt `attempt`'s replay at step
/// `step` (its `Init::from` may name another; [`crate::replay`] follows the chain).
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct Source {
    /// The source attempt's id.
    pub attempt: String,
    /// The step of the source whose state the attempt starts from (ms since the source's
    /// start; the source's log entries before it were applied, none at or after it).
    pub step: u64,
}

impl Source {
    /// The step's time: seconds since the source's start (1 ms steps).
    pub fn t_s(&self) -> f64 {
        self.step as f64 / 1000.0
    }
}

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
    pub what: Logged,
}

/// What an entry applied: a command, or the mark of an instructor's intervention.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(untagged)]
pub enum Logged {
    /// A command, in its log form (`{"c": name, …}`).
    Command(Command),
    /// An instructor's command counted as an intervention (`{"c": "intervention"}`).
    Intervention(Intervention),
}

/// The intervention mark's log form.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(tag = "c", rename_all = "snake_case")]
pub enum Intervention {
    /// `{"c": "intervention"}`.
    Intervention,
}

/// Writes one attempt's log.
pub struct Writer {
    enc: DeflateEncoder<Vec<u8>>,
    last_step: u64,
    last_input: Option<Vec<i32>>,
    /// Uncompressed bytes written.
    raw_bytes: u64,
    /// Entries written (inputs equal to the last one are not).
    entries: usize,
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
            entries: 0,
        }
    }

    /// Appends an entry. An input equal to the last one is skipped (applying it again
    /// changes nothing); any other entry forgets the last input, since a mode change
    /// clears the applied sticks and the same input then matters again.
    pub fn push(&mut self, entry: &Entry) {
        let dk = entry.k.saturating_sub(self.last_step);
        let line = match &entry.what {
            Logged::Command(Command::Input(input)) => {
                let v = input.quanta();
                if self.last_input.as_ref() == Some(&v) {
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
                self.last_input = Some(v);
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
        self.entries += 1;
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

    /// Entries written so far: the length of [`decode`]'s list for this log.
    pub fn entries(&self) -> usize {
        self.entries
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
            entries.push(Entry {
                k: step,
                what: Logged::Command(Command::Input(super::StickInput::from_quanta(&v))),
            });
            last = Some(v);
        } else {
            let mut value: serde_json::Value =
                serde_json::from_slice(line).map_err(|e| err(e.to_string()))?;
            let dk = value
                .as_object_mut()
                .and_then(|o| o.remove("dk"))
                .and_then(|d| d.as_u64())
                .ok_or_else(|| err("no step (dk)".into()))?;
            step += dk;
            let what = logged(value).map_err(err)?;
            last = None;
            entries.push(Entry { k: step, what });
        }
    }
    Ok(entries)
}

/// A logged entry's object (without `dk`) read back: the intervention mark or a command.
fn logged(value: serde_json::Value) -> Result<Logged, String> {
    if value.get("c").and_then(|c| c.as_str()) == Some("intervention") {
        return Ok(Logged::Intervention(Intervention::Intervention));
    }
    serde_json::from_value::<Command>(value)
        .map(Logged::Command)
        .map_err(|e| e.to_string())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A logged stick input from its values in quanta.
    pub(super) fn input(v: &[i32]) -> Logged {
        Logged::Command(Command::Input(super::super::StickInput::from_quanta(v)))
    }

    /// A format-1 log as the server has written it since issue 16 (before commands were
    /// logged as themselves): hand-written lines of every kind of entry, keys in serde_json's
    /// sorted order. It decodes to the commands it names, and writing those commands again
    /// gives back the same bytes.
    #[test]
    fn a_format_1_log_decodes_and_is_written_again_byte_for_byte() {
        let text = concat!(
            "[5,2,100,19,-3]\n",
            "[20,2,-50]\n",
            "{\"c\":\"settings\",\"dk\":3,\"method\":\"closed\",\"mode\":\"cartesian\",\"speed\":0.5}\n",
            "{\"c\":\"release\",\"dk\":0}\n",
            "[1,2,50,19,3]\n",
            "{\"answer\":\"leak\",\"c\":\"diagnose\",\"dk\":1}\n",
            "{\"c\":\"fault\",\"dk\":2,\"fault\":{\"arm\":1,\"joint\":3,\"kind\":\"leak\",\"value\":1e-11}}\n",
            "{\"c\":\"fault\",\"dk\":0,\"fault\":{\"arm\":0,\"kind\":\"supply_drop\",\"value\":3000000.0}}\n",
            "{\"c\":\"clear_faults\",\"dk\":0}\n",
            "{\"c\":\"current\",\"dk\":4,\"heading_deg\":200.0,\"speed_m_s\":0.8}\n",
            "{\"c\":\"intervention\",\"dk\":0}\n",
        );
        let mut enc = DeflateEncoder::new(Vec::new(), Compression::default());
        enc.write_all(text.as_bytes()).unwrap();
        let entries = decode(&enc.finish().unwrap()).unwrap();
        let steps: Vec<u64> = entries.iter().map(|e| e.k).collect();
        assert_eq!(steps, [5, 25, 28, 28, 29, 30, 32, 32, 32, 36, 36]);
        let mut v = vec![0; INPUT_VALUES];
        v[2] = 50;
        v[19] = -3;
        assert_eq!(entries[1].what, input(&v));
        let Logged::Command(Command::Settings(s)) = &entries[2].what else {
            panic!("settings: {:?}", entries[2].what);
        };
        assert_eq!(
            s.control_mode,
            Some(crate::protocol::ControlMode::Cartesian)
        );
        assert_eq!(
            s.control_method,
            Some(crate::protocol::ControlMethod::Closed)
        );
        assert_eq!(s.arm_speed, Some(0.5));
        assert_eq!(entries[3].what, Logged::Command(Command::Release));
        let Logged::Command(Command::InjectFault { fault }) = &entries[6].what else {
            panic!("fault: {:?}", entries[6].what);
        };
        assert_eq!(fault.arm, seaarms_core::sim::Arm::Right);
        assert_eq!(fault.fault.joint(), Some(3));
        let Logged::Command(Command::SetCurrent(c)) = &entries[9].what else {
            panic!("current: {:?}", entries[9].what);
        };
        assert_eq!((c.speed_m_s, c.heading_deg), (0.8, 200.0));
        assert_eq!(
            entries[10].what,
            Logged::Intervention(Intervention::Intervention)
        );
        let mut w = Writer::new();
        for e in &entries {
            w.push(e);
        }
        let mut again = String::new();
        DeflateDecoder::new(&w.finish()[..])
            .read_to_string(&mut again)
            .unwrap();
        assert_eq!(again, text);
    }

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
                what: input(&v),
            };
            w.push(&e);
            all.push(e);
            if k % 100 == 50 {
                let e = Entry {
                    k: k * 20,
                    what: Logged::Command(Command::InjectFault {
                        fault: (&FaultEntry {
                            arm: 1,
                            kind: "leak".into(),
                            joint: Some(3),
                            value: 1e-11,
                        })
                            .try_into()
                            .unwrap(),
                    }),
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
                what: tests::input(&v),
            });
        }
        let bytes = w.finish().len();
        println!("busy minute: {} B raw, {bytes} B compressed", w.raw_bytes());
        assert!(bytes < 50_000, "{bytes}");
    }
}

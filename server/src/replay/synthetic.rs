//! A free-play attempt of any length for the replay's benchmarks and tests (a 2-hour attempt
//! cannot be recorded in real time): the same [`Live`] a session has, in the `training`
//! scenario (sea water), driven by a fixed stick pattern — every 0.25 s one of six axes of
//! both arms at +0.8 or −0.6, and the shoulders alternately pressed down (into the seabed,
//! every contact of the step in use) and raised every 10 s — and recorded as a session records
//! it ([`Live::take_records`] every simulated second).

use std::sync::Arc;

use seaarms_core::Model;

use crate::catalogue::Scenario;
use crate::sessions::command::{ArmSticks, Command, StickInput};
use crate::sessions::record::RecordMsg;
use crate::sessions::{AttemptStop, Live};

use super::{Init, ReplayError};

/// A recorded synthetic attempt.
pub struct SyntheticAttempt {
    /// Its initial conditions.
    pub init: Init,
    /// Its whole input log (the pieces in order).
    pub inputs: Vec<u8>,
    /// Every record the recorder would have got (started, input pieces, ended).
    pub records: Vec<RecordMsg>,
    /// Its length (s).
    pub sim_seconds: f64,
}

/// Records a `seconds`-long free-play attempt of session `session` (an id of the records),
/// calling `observe` after every step.
pub fn free_play(
    models: &[Arc<Model>; 2],
    session: &str,
    seconds: u64,
    observe: &mut dyn FnMut(&Live),
) -> Result<SyntheticAttempt, ReplayError> {
    let record = |e: &dyn std::fmt::Display| ReplayError::Record(e.to_string());
    let scenario = Scenario::resolve("training").ok_or_else(|| record(&"no `training`"))?;
    let mut live =
        Live::new(session, models, &scenario, None, None, 1, None).map_err(|e| record(&e))?;
    let mut records = Vec::new();
    for i in 0..seconds * 4 {
        let mut axes = [0.0; 6];
        axes[((i / 8) % 6) as usize] = if (i / 3) % 2 == 0 { 0.8 } else { -0.6 };
        axes[1] = if (i / 40) % 2 == 0 { -1.0 } else { 0.7 };
        let input = StickInput {
            seq: i + 1,
            arms: [ArmSticks { axes, grip: 0.0 }; 2],
            ..StickInput::default()
        };
        live.apply(&Command::Input(input)).map_err(|e| record(&e))?;
        for _ in 0..250 {
            live.advance();
            observe(&live);
        }
        if i % 4 == 3 {
            records.extend(live.take_records(true));
        }
    }
    live.end_attempt(AttemptStop::Left);
    records.extend(live.take_records(false));
    let (mut init, mut inputs) = (None, Vec::new());
    for msg in &records {
        match msg {
            RecordMsg::AttemptStarted(a) => {
                init = Some(serde_json::from_value(a.init.clone()).map_err(|e| record(&e))?);
            }
            RecordMsg::AttemptInputs { bytes, .. } => inputs.extend_from_slice(bytes),
            _ => {}
        }
    }
    Ok(SyntheticAttempt {
        init: init.ok_or_else(|| record(&"no attempt started"))?,
        inputs,
        records,
        sim_seconds: live.sim().time_s(),
    })
}

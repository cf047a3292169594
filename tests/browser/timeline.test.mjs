//! The debrief timeline draws one marker per strike (pure, no browser): in an exercise the
//! assessment's notice (`exercise` event, kind `strike`/`obstacle`, at the next 100 Hz
//! sample) and the core's `strike` record (sent once the impact's peak is known, at most
//! sim::STRIKE_WINDOW_S = 0.2 s later) are the same strike; a strike the exercise does not
//! penalise (the box, the panel) and every strike in free play keep their record.

import { test } from 'node:test';
import assert from 'node:assert/strict';
import { oneMarkPerStrike, eventCategory } from '../../web/timeline.js';

test('one timeline marker per strike', () => {
  const notice = { t: 1.0, kind: 'exercise', detail: { kind: 'strike', text: 'Right arm struck the seabed at 0.18 m/s' } };
  const same = { t: 1.2, kind: 'strike', detail: { arm: 'right', partner: 'seabed', impact_speed_m_s: 0.18, peak_force_n: 4400 } };
  const box = { t: 5.0, kind: 'strike', detail: { arm: 'left', partner: 'box', impact_speed_m_s: 0.1, peak_force_n: 900 } };
  const grasp = { t: 5.1, kind: 'grasp', detail: { state: 'one_on_surface' } };
  const kept = oneMarkPerStrike([notice, same, box, grasp]);
  assert.deepEqual(kept, [notice, box, grasp]);
  assert.deepEqual(kept.map(eventCategory), ['strike', 'strike', 'grasp']);
  // free play: no notices, every record stays
  assert.deepEqual(oneMarkPerStrike([same, box]), [same, box]);
  // a record long after a notice is another strike
  const later = { ...same, t: 1.5 };
  assert.deepEqual(oneMarkPerStrike([notice, later]), [notice, later]);
});

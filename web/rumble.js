// Force cues (issue 28): the real Magnum arms are master/slave with force reflection (Lim
// §1.1); a gamepad can at least rumble. Each state frame's selected arm drives the pad's
// `vibrationActuator.playEffect('dual-rumble', …)`: the strong motor scales with the arm's
// contact force — the held load on the jaw (`arms.*.contact_force_n`) or the arm pressing on
// the world (`arms.*.touch.total_force_n`: seabed, box, panel, vehicle, other arm), whichever
// is larger — the weak one buzzes while the load slips (`arms.*.slipping`) or a relief valve
// is open (`relief_open`), and a strike (the arm's `strikes` count rising: the server's
// strike events) gives a full jolt. A pad without an actuator (or a browser without the API)
// gets nothing, without an error. Beside the task panel, a gauge shows the same contact force
// and the arm's highest line pressure.

/** Jaw force (N) that gives full rumble and fills the gauge: the Magnum jaw's clamp force,
 * 150 kgf (Lim Table 1-1; server/core hydraulics JawParams `clamp_force_n`). */
export const JAW_FORCE_FULL_N = 150 * 9.80665;
/** Line pressure gauge: full scale, and the marks at the supply (6.89 MPa, Lim Table 1-1
 * "operating pressure") and the relief setting (1.10 × supply, server/core HydraulicParams). */
export const PRESSURE_FULL_PA = 8e6;
export const SUPPLY_PA = 6.89e6;
export const RELIEF_PA = 1.1 * SUPPLY_PA;
/** Below this share of the full force the strong motor stays still (no buzz at a touch). */
const FORCE_FLOOR = 0.03;
/** One effect per this many ms at most; each lasts a little longer so they join up. */
const EFFECT_PERIOD_MS = 100;
const EFFECT_MS = 140;
const STRIKE_MS = 300;

/** An arm frame's contact force (N): its held load or its push on the world, the larger. */
export function contactForce(arm) {
  return Math.max(Math.hypot(...arm.contact_force_n), arm.touch?.total_force_n ?? 0);
}

/** Rumble magnitudes {strong, weak} in [0, 1] for one arm's frame and whether a strike just
 * happened (pure; the page and the tests use it). */
export function rumbleFor(arm, strike) {
  const f = contactForce(arm) / JAW_FORCE_FULL_N;
  let strong = f > FORCE_FLOOR ? Math.min(1, 0.25 + 0.75 * f) : 0;
  let weak = 0;
  if (arm.slipping) weak = Math.max(weak, 0.8);
  if (arm.relief_open.some(Boolean)) weak = Math.max(weak, 0.5);
  if (strike) { strong = 1; weak = 1; }
  return { strong, weak };
}

export class ForceCues {
  /** @param pads() the pads to rumble (web/input.js pads()); gaugeEl the gauge's element */
  constructor(pads, gaugeEl) {
    this.pads = pads;
    this.el = gaugeEl;
    this.lastAt = 0;
    this.strikes = null;
    this.played = []; // the effects asked for, for tests: {strong, weak, ms}
    if (gaugeEl) {
      gaugeEl.innerHTML = `<div class="g-row"><span class="k">contact force</span> <b data-g="force">0</b> N
        <span class="g-bar"><span class="g-fill" data-g="force-bar"></span></span></div>
        <div class="g-row"><span class="k">line pressure</span> <b data-g="p">0.0</b> MPa
        <span class="g-bar"><span class="g-fill" data-g="p-bar"></span><span class="g-mark" data-g="supply" title="supply ${(SUPPLY_PA / 1e6).toFixed(2)} MPa"></span><span class="g-mark relief" data-g="relief" title="relief ${(RELIEF_PA / 1e6).toFixed(2)} MPa"></span></span></div>
        <div class="g-row" title="Grip load: the share of the friction the jaw's clamp can hold that the load uses (100 %: it slips)"><span class="k">grip load</span> <b data-g="grip">—</b>
        <span class="g-bar"><span class="g-fill" data-g="grip-bar"></span></span></div>`;
      this.g = Object.fromEntries([...gaugeEl.querySelectorAll('[data-g]')].map((n) => [n.dataset.g, n]));
      this.g.supply.style.left = `${(100 * SUPPLY_PA / PRESSURE_FULL_PA).toFixed(1)}%`;
      this.g.relief.style.left = `${(100 * RELIEF_PA / PRESSURE_FULL_PA).toFixed(1)}%`;
    }
  }

  /** A state frame and the arm the sticks drive. */
  update(state, side) {
    const arm = state.arms[side];
    // a strike of this arm since the last frame (a new side starts from its own count)
    const strike = this.side === side && this.strikes !== null && arm.strikes > this.strikes;
    this.side = side;
    this.strikes = arm.strikes;
    this.gauge(arm);
    const { strong, weak } = rumbleFor(arm, strike);
    const now = performance.now();
    // a strike or the start of a slip is felt at once, whatever was played just before
    const onset = strike || (arm.slipping && !this.slipping);
    this.slipping = arm.slipping;
    if ((strong > 0 || weak > 0) && (onset || now - this.lastAt >= EFFECT_PERIOD_MS)) {
      this.lastAt = now;
      this.play({ strong, weak, ms: strike ? STRIKE_MS : EFFECT_MS });
    }
  }

  play({ strong, weak, ms }) {
    this.played.push({ strong, weak, ms });
    if (this.played.length > 50) this.played.shift();
    for (const p of this.pads()) {
      const act = p?.vibrationActuator;
      if (!act || typeof act.playEffect !== 'function') continue;
      // a refused effect (no permission, a pad that lost its motors) is no error of ours
      Promise.resolve(act.playEffect('dual-rumble', { duration: ms, strongMagnitude: strong, weakMagnitude: weak }))
        .catch(() => {});
    }
  }

  gauge(arm) {
    if (!this.g) return;
    const f = contactForce(arm);
    const p = Math.max(...arm.p_in, ...arm.p_out);
    this.g.force.textContent = f.toFixed(0);
    this.g['force-bar'].style.width = `${Math.min(100, 100 * f / JAW_FORCE_FULL_N).toFixed(1)}%`;
    this.g.p.textContent = (p / 1e6).toFixed(1);
    this.g['p-bar'].style.width = `${Math.min(100, 100 * p / PRESSURE_FULL_PA).toFixed(1)}%`;
    this.el.classList.toggle('relief', arm.relief_open.some(Boolean));
    // λ against the static friction limits, capped at 100 % (a sliding jaw is at its limit)
    const grip = arm.holding ? Math.min(1, arm.grip_load) : null;
    this.g.grip.textContent = grip === null ? '—' : arm.slipping ? 'slipping' : `${Math.round(100 * grip)} %`;
    this.g['grip-bar'].style.width = `${grip === null ? 0 : (100 * (arm.slipping ? 1 : grip)).toFixed(1)}%`;
    this.el.classList.toggle('slipping', !!arm.slipping);
  }
}

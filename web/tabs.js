// One driver per session among this browser's tabs. Tabs of one browser share the stored
// session (localStorage), so a second tab would join as a second trainee and its zero input
// would fight the first one's. Before it connects, a tab asks the others over a
// BroadcastChannel whether one drives that session; if so the trainee chooses to watch (the
// tab connects read-only: role=observer with the same token) or to take control (the driving
// tab is told and turns into an observer, with a button to take control back).

const CHANNEL = 'seaarms.tabs';
/** How long a tab waits for another to answer "I drive this session" (ms). */
const ASK_MS = 300;

export class TabGuard {
  /**
   * @param el element for the prompt and the "watching" note
   * @param onTakenOver() called when another tab takes control of this tab's session
   */
  constructor(el, { onTakenOver }) {
    this.el = el;
    this.id = Math.random().toString(36).slice(2);
    this.session = null; // session this tab drives (null: none, or watching)
    this.waiting = null; // resolver of a pending ask
    this.ch = typeof BroadcastChannel === 'function' ? new BroadcastChannel(CHANNEL) : null;
    if (this.ch) this.ch.onmessage = (e) => this.onMessage(e.data, onTakenOver);
  }

  onMessage(m, onTakenOver) {
    if (!m || m.from === this.id) return;
    if (m.type === 'ask' && m.session === this.session) this.ch.postMessage({ type: 'driving', session: m.session, from: this.id, to: m.from });
    else if (m.type === 'driving' && m.to === this.id) this.waiting?.(true);
    else if (m.type === 'take' && m.session === this.session) {
      this.session = null;
      onTakenOver();
    }
  }

  /** Records that this tab drives `session` (its hello said role trainee), or none. */
  driving(session) { this.session = session; }

  /** Whether another tab of this browser drives `session`. */
  anotherDriving(session) {
    if (!this.ch || !session) return Promise.resolve(false);
    return new Promise((resolve) => {
      const timer = setTimeout(() => { this.waiting = null; resolve(false); }, ASK_MS);
      this.waiting = (v) => { clearTimeout(timer); this.waiting = null; resolve(v); };
      this.ch.postMessage({ type: 'ask', session, from: this.id });
    });
  }

  /** Tells the other tabs that this one takes control of `session`. */
  take(session) {
    this.ch?.postMessage({ type: 'take', session, from: this.id });
  }

  /** Asks the trainee: resolves 'watch' or 'take'. */
  choose() {
    return this.show('Another tab is driving this session.', [['watch', 'Watch'], ['take', 'Take control']]);
  }

  /** Shows that this tab watches; resolves when the trainee asks to take control. */
  watching(text) {
    return this.show(text, [['take', 'Take control']], 'tab-note');
  }

  hide() { this.el.hidden = true; }

  show(text, buttons, cls = 'tab-prompt') {
    this.el.className = cls;
    this.el.replaceChildren();
    const p = document.createElement('span');
    p.textContent = text;
    this.el.append(p);
    this.el.hidden = false;
    return new Promise((resolve) => {
      for (const [value, label] of buttons) {
        const b = document.createElement('button');
        b.type = 'button';
        b.dataset.choice = value;
        b.textContent = label;
        b.addEventListener('click', () => { this.hide(); resolve(value); });
        this.el.append(b);
      }
    });
  }
}

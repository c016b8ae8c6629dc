// catenary_monitor console: the page. Plain JS, no library. It shows what the monitor published
// (levels, messages, alarm states are the monitor's decisions); it only formats and draws.
'use strict';

const SVGNS = 'http://www.w3.org/2000/svg';
const KN = 1e-3;
const SILENCE_S = 30;        // a silenced alarm sounds again after this (IMO MSC.302(87))
const REPEAT_S = 5;          // an unacknowledged ERROR beeps again every REPEAT_S
const SERVER_TIMEOUT_S = 2.5;  // no stream message for this long: the console server is gone
const NO_FRAME = { alarms: [] };  // what sound() is given before the first frame

const S = {
  config: null, frame: null, line: null, span: 3600, tab: 'active',
  audio: null, mutedUntil: 0, lastBeep: 0, knownErrors: new Set(), beeps: 0,
  lastMessage: 0, serverLost: false, configPending: false, replay: { t: 0, playing: false, speed: 10, last: 0 },
  trendAt: 0, bench: location.search.includes('bench=1') ? [] : null,
  operator: null,  // the signed-in operator's name (a token console); the token is in sessionStorage
  liveStart: 0,    // when the page began to wait for live data (performance.now() ms)
  stream: { state: 'connecting', why: '', failures: 0, retryAt: 0, abort: null, restart: false },
};
window.cmConsole = S;  // for the tests and the latency benchmark

const $ = (id) => document.getElementById(id);
function el(tag, attrs, text) {
  const e = document.createElement(tag);
  for (const [k, v] of Object.entries(attrs || {})) e.setAttribute(k, v);
  if (text !== undefined) e.textContent = text;
  return e;
}
function svg(tag, attrs, text) {
  const e = document.createElementNS(SVGNS, tag);
  for (const [k, v] of Object.entries(attrs || {})) e.setAttribute(k, v);
  if (text !== undefined) e.textContent = text;
  return e;
}
const num = (v, digits, scale) => (v === null || v === undefined ? '—' : (v * (scale || 1)).toFixed(digits));
function clock(t, withDate) {
  if (t === null || t === undefined) return '—';
  const d = new Date(t * 1000);
  const p = (n) => String(n).padStart(2, '0');
  const hms = `${p(d.getHours())}:${p(d.getMinutes())}:${p(d.getSeconds())}`;
  return withDate ? `${d.getFullYear()}-${p(d.getMonth() + 1)}-${p(d.getDate())} ${hms}` : hms;
}
function ago(s) {
  if (s === null || s === undefined) return 'never';
  if (s < 60) return `${s.toFixed(1)} s`;
  if (s < 3600) return `${Math.floor(s / 60)} min ${Math.floor(s % 60)} s`;
  return `${(s / 3600).toFixed(1)} h`;
}

// ---------------------------------------------------------------- start
async function start() {
  S.liveStart = performance.now();
  setInterval(watchdog, 250);
  S.config = await fetchConfig();
  $('mode').textContent = S.config.mode === 'live' ? 'LIVE' : 'REPLAY';
  buildLines();
  bindPickers();
  $('ack-all').addEventListener('click', () => acknowledge('all'));
  bindAccess();
  $('tab-active').addEventListener('click', () => showTab('active'));
  $('tab-history').addEventListener('click', () => showTab('history'));
  $('tab-shelved').addEventListener('click', () => showTab('shelved'));
  $('shelve-form').addEventListener('submit', (ev) => {
    ev.preventDefault();
    shelve($('shelve-line').value, $('shelve-condition').value, parseFloat($('shelve-duration').value));
  });
  $('sound').addEventListener('click', soundButton);
  unlockAudio();
  document.addEventListener('click', () => { if (S.audio) S.audio.resume().then(updateSoundButton); }, { once: true });
  if (S.config.mode === 'live') startLive(); else startReplay();
  setInterval(refreshTrend, 2000);
  let resized = 0;
  window.addEventListener('resize', () => { clearTimeout(resized); resized = setTimeout(refreshTrend, 200); });
}

// Everything drawn per line: tiles, level chips, plan, trend picker (again when the lines change).
function buildLines() {
  const names = S.config.lines.map((l) => l.name);
  if (!names.includes(S.line)) S.line = names.includes('line_11') ? 'line_11' : names[0];
  buildTiles();
  buildPlan();
  buildPickers();
  buildShelveForm();
}

// A console started without --params-file learns the lines from /diagnostics after the page
// loaded: a frame naming other lines than the page's fetches the configuration again and
// rebuilds the page's lines (no reload).
async function reconfigure() {
  if (S.configPending) return;
  S.configPending = true;
  try {
    const config = await (await fetch('/api/config')).json();
    S.config = config;
    buildLines();
    if (S.frame) render(S.frame);
    refreshTrend();
  } catch (e) { /* the server is gone: the banner says so; the next frame tries again */ }
  finally { S.configPending = false; }
}

function sameLines(frame) {
  const have = S.config.lines;
  return frame.lines.length === have.length && frame.lines.every((v, k) => v.name === have[k].name);
}

// Seconds since the newest frame arrived, by the browser's own clock (live only): every age on
// the page adds it, so ages keep counting while the console server is gone.
function sinceFrame() {
  if (!S.config || S.config.mode !== 'live' || !S.lastMessage) return 0;
  return (performance.now() - S.lastMessage) / 1000;
}

// The configuration, asked again with backoff until the console server answers (the banner
// says so meanwhile; server_link.js).
function fetchConfig() {
  return cmLink.config('console', (why) => { S.stream.why = why; }, retryPause);
}

function retryPause(delay) {
  const wait = cmLink.jitter(delay);
  S.stream.state = 'retrying';
  S.stream.failures += 1;
  S.stream.retryAt = performance.now() + wait * 1000;
  return cmLink.sleep(wait);
}

// The frames come over GET /api/stream (server_link.js): the operator's token goes along (a
// reserved stream, which a flood of streams cannot displace), and every failure is seen and
// retried with backoff: a refusal (503, 401, ...), a cut, a silent stream.
async function startLive() {
  const st = S.stream;
  for (let delay = cmLink.RETRY_MIN_S; ; delay = cmLink.next(delay)) {
    const ctrl = new AbortController();
    st.abort = ctrl;
    let frames = 0;
    try {
      st.state = 'connecting';
      const reader = await cmLink.open(TOKEN_KEY, ctrl.signal, signedOut);
      st.state = 'open';
      frames = await cmLink.read(reader, ctrl, liveFrame, (why) => { st.why = why; });
      st.why = 'the stream ended';
    } catch (e) {
      if (!ctrl.signal.aborted) st.why = e && e.message ? e.message : String(e);
    }
    if (st.restart) { st.restart = false; delay = cmLink.RETRY_MIN_S / 2; continue; }  // signed in
    if (frames > 0) delay = cmLink.RETRY_MIN_S;
    await retryPause(delay);
  }
}

// One frame of the live stream: rendered, the server heard.
function liveFrame(frame) {
  S.lastMessage = performance.now();
  S.serverLost = false;
  S.stream.why = '';
  render(frame);
}

// A new stream at once (with the token just signed in with: a reserved one).
function restartStream() {
  const st = S.stream;
  if (!st.abort || !S.config || S.config.mode !== 'live') return;
  st.restart = true;
  st.abort.abort();
}

function startReplay() {
  const r = S.replay, c = S.config;
  $('replay-bar').hidden = false;
  $('ack-all').disabled = true;
  $('sound').hidden = true;
  const slider = $('slider');
  slider.min = c.t_start; slider.max = c.t_end; slider.value = c.t_start;
  r.t = c.t_start;
  $('replay-files').textContent = (c.files || []).map((f) => f.split('/').pop()).join(', ');
  slider.addEventListener('input', () => { r.t = parseFloat(slider.value); fetchFrame(true); });
  $('play').addEventListener('click', togglePlay);
  $('speed').addEventListener('change', () => { r.speed = parseFloat($('speed').value); });
  document.addEventListener('keydown', (e) => { if (e.code === 'Space') { e.preventDefault(); togglePlay(); } });
  setInterval(() => {
    if (!r.playing) return;
    const now = performance.now();
    r.t = Math.min(r.t + (now - r.last) / 1000 * r.speed, c.t_end);
    r.last = now;
    if (r.t >= c.t_end) togglePlay();
    slider.value = r.t;
    fetchFrame(false);
  }, 250);
  fetchFrame(true);
}

function togglePlay() {
  const r = S.replay;
  r.playing = !r.playing;
  r.last = performance.now();
  if (r.playing && r.t >= S.config.t_end) r.t = S.config.t_start;
  $('play').textContent = r.playing ? '❚❚' : '▶';
}

let framePending = false, frameAgain = false;
async function fetchFrame(withTrend) {
  // One request at a time; a position asked for meanwhile is fetched right after (the page
  // always ends at the slider's last position).
  if (framePending) { frameAgain = true; return; }
  framePending = true;
  try {
    const frame = await (await fetch(`/api/frame?t=${S.replay.t}`)).json();
    S.lastMessage = performance.now();
    render(frame);
    if (withTrend || performance.now() - S.trendAt > 1000) refreshTrend();
  } finally {
    framePending = false;
    if (frameAgain) { frameAgain = false; fetchFrame(true); }
  }
}

// ---------------------------------------------------------------- tiles
function buildTiles() {
  const box = $('tiles'), chips = $('levels');
  box.textContent = '';
  chips.textContent = '';
  for (const line of S.config.lines) {
    const t = el('div', { class: 'tile', 'data-line': line.name, 'data-level': 'STALE' });
    t.innerHTML = `<div class="tile-head"><span class="name"></span><span class="badge"></span></div>
      <div class="bar"><div class="fill"></div><div class="mark"></div><div class="bar-label"></div></div>
      <dl class="vals"><dt>anchor margin</dt><dd class="v-margin"></dd><dt class="k-uplift">uplift</dt><dd class="v-uplift"></dd>
      <dt>safety factor</dt><dd class="v-sf"></dd><dt>uplift in</dt><dd class="v-ttu"></dd>
      <dt title="${TIDE_R}">tide to lift, R held</dt><dd class="v-tide" title="${TIDE_R}"></dd>
      <dt class="x-tidel" title="${TIDE_L}">tide to lift, chain length held</dt><dd class="v-tidel x-tidel" title="${TIDE_L}"></dd>
      <dt class="x-span" title="${SPAN}">span</dt><dd class="v-span x-span" title="${SPAN}"></dd>
      <dt class="x-upper" title="uplift bound: the anchor's force at most, with the waves (the window's peak tension) and the sensors' accuracy">uplift bound</dt><dd class="v-upper x-upper"></dd>
      <dt class="x-wave" title="wave-frequency tension: half the range of the readings over wave_window">wave tension</dt><dd class="v-wave x-wave"></dd>
      <dt class="x-drag">drag margin</dt><dd class="v-drag x-drag"></dd>
      ${channelRows(line.channels || [])}
</dl>
      <div class="msg"></div><div class="foot"><span class="v-model" title="the model that answered"></span> · <span class="age"></span><span class="v-fatigue" title="chain fatigue: Miner's damage (1: the S-N curve's failure) and the life left at the last day's rate"></span><span class="alarm-st"></span><span class="sensor old"></span></div>`;
    t.querySelector('.name').textContent = line.name;
    const warn = line.mbl ? 1 / S.config.safety_factor_warn : null;
    const mark = t.querySelector('.mark');
    if (warn !== null) mark.style.left = `${100 * warn}%`; else mark.hidden = true;
    t.addEventListener('click', () => selectLine(line.name));
    box.appendChild(t);
    const chip = el('button', { class: 'chip', 'data-chip': line.name }, line.name.replace('line_', ''));
    chip.addEventListener('click', () => { selectLine(line.name); t.scrollIntoView({ block: 'nearest' }); });
    chips.appendChild(chip);
  }
}

// A load cell's channels (docs/channels.md): one row each, its state from channel_states.
const CHANNEL_WORDS = ['ok', 'silent', 'stuck', 'out of line', 'none'];

function channelRows(topics) {
  if (topics.length < 2) return '';
  // each channel named by what tells it from the others (its topic less their common folder)
  let cut = topics[0].lastIndexOf('/') + 1;
  while (cut > 0 && !topics.every((x) => x.startsWith(topics[0].slice(0, cut)))) {
    cut = topics[0].lastIndexOf('/', cut - 2) + 1;
  }
  const esc = (x) => x.replace(/[&<>"]/g, (c) => ({ '&': '&amp;', '<': '&lt;', '>': '&gt;', '"': '&quot;' })[c]);
  return topics.map((topic, j) => {
    const tip = `load-cell channel ${esc(topic)}`;
    return `<dt class="x-ch" title="${tip}">channel ${esc(topic.slice(cut))}</dt><dd class="v-ch" data-ch="${j}" title="${tip}"></dd>`;
  }).join('');
}

function channelStates(code, n) {
  // channel_states: sum code_i 5^i in the order of tension_topics; null: unknown
  if (code === null || code === undefined) return null;
  const out = [];
  let c = Math.round(code);
  for (let j = 0; j < n; j++) { out.push(c % 5); c = Math.floor(c / 5); }
  return out;
}

function renderChannels(t, view) {
  const cells = t.querySelectorAll('.v-ch');
  if (!cells.length) return;
  const states = channelStates(view.channel_states, cells.length);
  cells.forEach((dd, j) => {
    const code = states ? states[j] : null;
    dd.textContent = code === null ? 'unknown' : CHANNEL_WORDS[code] || 'unknown';
    dd.className = 'v-ch ' + (code === null ? '' : code === 0 ? '' : 'warn');
  });
}

// The two tide margins (docs/node.md): the monitor's (R held; its warning and time to uplift
// follow it) and, with chain_length set, the chain's length and span held.
const TIDE_R = 'tide_margin: the tide rise that lifts the anchor with the horizontal tension R held '
  + 'where it is now (a dock free to drift under a steady load); the tide warning and the time to uplift follow it';
const TIDE_L = 'tide_margin_at_length: the tide rise that lifts the anchor with the chain\'s length and '
  + 'span held (a dock at rest on chains of fixed length: the nearer one there)';

const SPAN = 'span: the hook-anchor distance the line is solved at: from the dock estimate (the dock\'s '
  + 'offset, every line\'s tension) where it has one for the line, else the installed anchor distance';

function renderChip(view, level) {
  const chip = document.querySelector(`.chip[data-chip="${view.name}"]`);
  if (!chip) return;
  const short = view.name.replace('line_', '');
  setText(chip, level === 'OK' ? short : `${short} ${level}`);
  chip.className = `chip lv-${level}`;
  chip.title = `${view.name}: ${level}: ${view.message}`;
}

function renderTile(view, lost, frame) {
  const t = document.querySelector(`.tile[data-line="${view.name}"]`);
  if (!t) return;
  const cfg = S.config.lines.find((l) => l.name === view.name) || {};
  const level = lost ? 'STALE' : view.level;
  t.dataset.level = level;
  t.classList.toggle('lost', lost);
  t.classList.toggle('unack', !lost && view.alarm_state === 'unacknowledged');
  t.classList.toggle('selected', view.name === S.line);
  const badge = t.querySelector('.badge');
  badge.textContent = level; badge.className = `badge ${level}`;
  const T = view.top_tension;
  const mbl = cfg.mbl || (view.safety_factor && T ? view.safety_factor * T : null);
  const frac = T !== null && T !== undefined && mbl ? T / mbl : null;
  const fill = t.querySelector('.fill');
  fill.style.width = `${frac === null ? 0 : Math.min(100, 100 * frac)}%`;
  fill.classList.toggle('over', frac !== null && frac > 1 / S.config.safety_factor_warn);
  t.querySelector('.bar-label').textContent = T === null || T === undefined ? 'no tension' :
    `${num(T, 0, KN)} kN` + (frac === null ? '' : ` · ${(100 * frac).toFixed(0)} % MBL`);
  const m = t.querySelector('.v-margin');
  m.textContent = `${num(view.anchor_margin, 2)} m`;
  m.className = 'v-margin ' + (view.anchor_margin !== null && view.anchor_margin < 0 ? 'bad' :
    (view.anchor_margin !== null && view.anchor_margin < S.config.anchor_margin_warn ? 'warn' : ''));
  // The uplift the alarm is raised on: the dynamic one (at the waves' peak tension) where it
  // exceeds the quasi-static one, which the title then gives.
  const u = t.querySelector('.v-uplift'), lift = view.uplift_shown;
  u.textContent = `${num(lift, 1, KN)} kN`;
  u.className = 'v-uplift ' + (lift > (cfg.allowed_uplift || 0) ? 'bad' : '');
  u.title = view.uplift_dynamic ? `at the waves' peak tension; quasi-static ${num(view.uplift_force, 1, KN)} kN` : '';
  setText(t.querySelector('.k-uplift'), view.uplift_dynamic ? 'uplift, wave peak' : 'uplift');
  const sf = t.querySelector('.v-sf');
  sf.textContent = num(view.safety_factor, 2);
  sf.className = 'v-sf ' + (view.safety_factor !== null && view.safety_factor < S.config.safety_factor_warn ? 'warn' : '');
  // Time to uplift at the tide's trend (null: the tide is not bringing uplift closer).
  const ttu = view.time_to_uplift;
  const tt = t.querySelector('.v-ttu');
  // Unknown (NaN: no trend yet) is not "never" (inf: the tide is not rising).
  const state = view.time_to_uplift_state;
  tt.textContent = ttu === null || ttu === undefined
    ? (state === 'not coming' ? 'not coming' : 'unknown')
    : ttu <= 0 ? 'lifted' : ago(ttu) + (view.time_to_uplift_view === 'chain length held' ? ' (chain length)' : '');
  tt.title = (ttu === null || ttu === undefined) && state !== 'not coming'
    ? 'time to uplift unknown, trend not known yet: the tide\'s trend needs half the trend window of depth (or the line has no solve)'
    : view.time_to_uplift_view && view.time_to_uplift_view !== 'none'
      ? `time to uplift, ${view.time_to_uplift_view}` : 'time to uplift';
  // A time in words ('42 min 0 s (chain length)') wraps.
  tt.className = 'v-ttu ' + (ttu !== null && ttu !== undefined && ttu < S.config.uplift_time_warn ? 'warn' : '') +
    (tt.textContent.length > 12 ? ' wrap' : '');
  // The two tide margins: R held (always), chain length held (where finite: chain_length set).
  const shown = (v) => v !== null && v !== undefined;
  const tide = t.querySelector('.v-tide'), tidel = t.querySelector('.v-tidel');
  tide.textContent = `${num(view.tide_margin, 2)} m`;
  tide.className = 'v-tide ' + (shown(view.tide_margin) && view.tide_margin < 0 ? 'bad' :
    (shown(view.tide_margin) && view.tide_margin < S.config.tide_margin_warn ? 'warn' : ''));
  t.querySelectorAll('.x-tidel').forEach((e) => { e.hidden = !shown(view.tide_margin_at_length); });
  tidel.textContent = shown(view.tide_margin_at_length) ? `${num(view.tide_margin_at_length, 2)} m` : '';
  tidel.className = 'v-tidel x-tidel ' + (shown(view.tide_margin_at_length) && view.tide_margin_at_length < 0 ? 'bad' : '');
  // The span solved at (docs/node.md): shown with the dock's geometry, its source beside it.
  const placed = cfg.hook_x !== null && cfg.hook_x !== undefined;
  t.querySelectorAll('.x-span').forEach((e) => { e.hidden = !(placed && shown(view.span)); });
  const moved = shown(view.span) && cfg.anchor_distance ? view.span - cfg.anchor_distance : null;
  // The source in the label, the move from the installed span beside the value (one row).
  const estimated = view.span_source === 'dock_estimate';
  setText(t.querySelector('dt.x-span'), estimated ? 'span, estimated' : 'span, installed');
  t.querySelector('.v-span').textContent = !shown(view.span) ? '' : estimated
    ? `${num(view.span, 2)} m (${moved >= 0 ? '+' : ''}${num(moved, 2)})`
    : `${num(view.span, 2)} m`;
  // The uplift bound within sensor accuracy and the drag margin: shown where configured.
  const up = view.uplift_force_upper, drag = view.drag_margin;
  t.querySelectorAll('.x-upper').forEach((e) => { e.hidden = !shown(up); });
  t.querySelectorAll('.x-drag').forEach((e) => { e.hidden = !shown(drag); });
  t.querySelectorAll('.x-wave').forEach((e) => { e.hidden = !shown(view.wave_tension); });
  t.querySelector('.v-wave').textContent = shown(view.wave_tension) ? `± ${num(view.wave_tension, 1, KN)} kN` : '';
  const vu = t.querySelector('.v-upper');
  vu.textContent = shown(up) ? `${num(up, 1, KN)} kN` : '';
  vu.className = 'v-upper x-upper ' + (shown(up) && up > (cfg.allowed_uplift || 0) ? 'warn' : '');
  // drag_state (docs/holding.md): 0 holding, 1 overloaded, 2 dragging (an ERROR).
  const vd = t.querySelector('.v-drag'), dstate = view.drag_state;
  const dword = dstate === 2 ? ' · DRAGGING' : dstate === 1 ? ' · overloaded' : '';
  vd.textContent = shown(drag) ? `${num(drag, 1, KN)}\u00a0kN${dword}` : '';
  vd.className = 'v-drag x-drag ' + (dstate === 2 ? 'bad' :
    (shown(drag) && drag < (S.config.drag_margin_warn || 0) ? 'warn' : ''));
  renderChannels(t, view);
  // Chain fatigue (docs/fatigue.md): Miner's damage and the life left at the last day's rate.
  const dmg = view.fatigue_damage, life = view.fatigue_life_left;
  const vf = t.querySelector('.v-fatigue');
  const years = shown(life) ? ` · ${life / 31557600 > 2 ? (life / 31557600).toFixed(1) + ' y' : (life / 86400).toFixed(1) + ' d'} left` : '';
  vf.textContent = shown(dmg) ? ` · fatigue D ${dmg.toPrecision(3)}${years}` : '';
  vf.className = 'v-fatigue ' + (shown(dmg) && dmg >= (S.config.fatigue_damage_warn || 1) ? 'warn' : '');
  setText(t.querySelector('.v-model'), (view.model || 'no model').replace(' catenary', ''));
  const msg = lost ? `monitor silent: last known ${view.level} at ${clock(frame.snapshot_t)}` : view.message;
  t.querySelector('.msg').textContent = msg;
  // An OK line's message says nothing the badge does not ('ok'): no row for it.
  t.querySelector('.msg').hidden = !lost && level === 'OK' && /^ok$/i.test(msg.trim());
  t.querySelector('.msg').title = msg;
  renderAge(t, view);
  setText(t.querySelector('.alarm-st'), (view.alarm_state && view.alarm_state !== 'normal' ? ` · alarm ${view.alarm_state}` : '')
    + (view.shelved ? ` · ${view.shelved_condition === 'all' ? '' : view.shelved_condition.replaceAll('_', ' ') + ' '}shelved until ${clock(view.shelved_until)}` : '')
    + (view.chattering ? ' · chattering' : ''));
  t.dataset.shelved = view.shelved ? 'true' : 'false';
  t.dataset.chattering = view.chattering ? 'true' : 'false';
  // The load cell's sanity (stuck, spike, over_mbl, slack, suspected_parted; the dock model's
  // inconsistent, suspect): check the sensor. 'unchecked' (not judged by the dock model) is quiet.
  const sensor = view.sensor_state || 'ok';
  t.dataset.sensorState = sensor;
  setText(t.querySelector('.sensor'), sensor !== 'ok' && sensor !== 'unchecked' ? ` · sensor ${sensor.replaceAll('_', ' ')}` : '');
  renderChip(view, level);
}

// The newest tension sample's age: the server's figure plus the time since that frame came.
function renderAge(t, view) {
  const age = view.age_s === null || view.age_s === undefined ? null : view.age_s + sinceFrame();
  const span = t.querySelector('.age');
  setText(span, `newest sample ${ago(age)} ago`);
  span.className = `age ${age !== null && age > S.config.tension_timeout ? 'old' : ''}`;
}

// Everything on the page that counts time: run by each frame and, between frames (and while the
// console server is gone), by the watchdog.
function renderTimes(frame) {
  for (const view of frame.lines) {
    const t = document.querySelector(`.tile[data-line="${view.name}"]`);
    if (t) renderAge(t, view);
  }
  renderBanner(frame);
  $('clock').textContent = clock(frame.now + sinceFrame(), S.config.mode !== 'live');
}

// ---------------------------------------------------------------- plan
function buildPlan() {
  const plan = $('plan');
  plan.textContent = '';
  const A = 24, B = 95;  // dock half beam, half length (plan units; bow up)
  plan.appendChild(svg('path', { class: 'plan-dock',
    d: `M ${-A} ${-B + 14} L 0 ${-B - 8} L ${A} ${-B + 14} L ${A} ${B} L ${-A} ${B} Z` }));
  plan.appendChild(svg('text', { x: 0, y: -B + 30, 'text-anchor': 'middle', class: 'muted' }, 'BOW'));
  const far = Math.max(...S.config.lines.map((l) => l.anchor_distance || 120));
  // Hooks where the params file puts them (x to the bow is up, y to port is left; REP 103),
  // else where the chain's direction leaves the outline.
  const placed = S.config.lines.every((l) => l.hook_x !== null && l.hook_x !== undefined && l.hook_y !== null && l.hook_y !== undefined);
  const halfL = Math.max(S.config.dock_length ? S.config.dock_length / 2 : 0, ...S.config.lines.map((l) => Math.abs(l.hook_x || 0)), 1e-9);
  const halfB = Math.max(S.config.dock_beam ? S.config.dock_beam / 2 : 0, ...S.config.lines.map((l) => Math.abs(l.hook_y || 0)), 1e-9);
  for (const line of S.config.lines) {
    const th = line.heading * Math.PI / 180;
    const dx = Math.sin(th), dy = -Math.cos(th);
    const k = Math.min(Math.abs(dx) > 1e-9 ? A / Math.abs(dx) : 1e9, Math.abs(dy) > 1e-9 ? B / Math.abs(dy) : 1e9);
    const hx = placed ? -A * line.hook_y / halfB : dx * k, hy = placed ? -B * line.hook_x / halfL : dy * k;
    const len = 95 * (line.anchor_distance || 120) / far;
    const ax = hx + dx * len, ay = hy + dy * len;
    const g = svg('g', { 'data-plan-line': line.name });
    g.appendChild(svg('line', { class: 'plan-chain c-STALE', x1: hx, y1: hy, x2: ax, y2: ay }));
    g.appendChild(svg('circle', { class: 'plan-anchor c-STALE', cx: ax, cy: ay, r: 6 }));
    const lift = svg('circle', { class: 'plan-lift', cx: ax, cy: ay, r: 12 });
    lift.style.display = 'none';
    g.appendChild(lift);
    const lx = ax + dx * 16, ly = ay + dy * 16 + 4;
    g.appendChild(svg('text', { class: 'plan-label', x: lx, y: ly, 'text-anchor': dx > 0.3 ? 'start' : dx < -0.3 ? 'end' : 'middle' },
      line.name.replace('line_', '')));
    g.appendChild(svg('title', {}, `${line.name}: heading ${line.heading.toFixed(0)}°`));
    g.addEventListener('click', () => selectLine(line.name));
    plan.appendChild(g);
  }
}

function renderPlan(frame, lost) {
  for (const view of frame.lines) {
    const g = document.querySelector(`[data-plan-line="${view.name}"]`);
    if (!g) continue;
    const level = lost ? 'STALE' : view.level;
    g.querySelector('.plan-chain').setAttribute('class', `plan-chain c-${level}`);
    g.querySelector('.plan-anchor').setAttribute('class', `plan-anchor c-${level}`);
    g.querySelector('.plan-lift').style.display = !lost && view.uplift_force > 0 ? '' : 'none';
    g.classList.toggle('sel', view.name === S.line);
  }
}

// ---------------------------------------------------------------- alarms
let alarmKey = '', historyKey = '';
function renderAlarms(frame, lost) {
  // Rebuilt only when something in the list changed (a button must not move under a click).
  const replay = S.config.mode !== 'live';
  const key = JSON.stringify([lost, S.tab, canAct(), frame.alarms]);
  if (key !== alarmKey) { alarmKey = key; renderActive(frame, lost, replay); }
  const last = frame.history[frame.history.length - 1];
  const hkey = JSON.stringify([frame.history.length, last]);
  if (hkey !== historyKey) { historyKey = hkey; renderHistory(frame); }
  const skey = JSON.stringify([lost, S.tab, canAct(), frame.shelved]);
  if (skey !== shelvedKey) { shelvedKey = skey; renderShelved(frame, lost, replay); }
  renderFlood(frame, lost);
  updateShelveForm(frame, lost, replay);
}

// The monitor's flood status (catenary_monitor: alarms, EEMUA 191): a banner naming the first
// out while it lasts, and the count of the flood window beside the list's title.
function renderFlood(frame, lost) {
  const f = frame.flood || {};
  const on = !!f.flood && !lost;
  const banner = $('flood-banner');
  banner.hidden = !on;
  if (on) {
    banner.dataset.flood = 'true';
    setText(banner, `ALARM FLOOD since ${clock(f.since)}: ${f.count} alarms raised in the flood window`
      + ` — first out: ${f.first_out} (raised ${clock(f.first_out_at)}); deal with it first`);
  } else delete banner.dataset.flood;
  $('flood').hidden = !on;
  setText($('flood'), on ? `FLOOD: ${f.count} raised` : '');
}
let shelvedKey = '';

// The selected alarm (a click on its row; else the list's first): its headline, what to do
// (the monitor's response text: cause, consequence, action) and every condition in full.
function pickedAlarm(frame) {
  const names = frame.alarms.map((a) => a.line);
  return names.includes(S.alarm) ? S.alarm : names[0];
}

function selectAlarm(line) {
  S.alarm = line;
  alarmKey = '';
  if (S.frame) render(S.frame);
}

function renderResponse(frame, lost) {
  const box = $('response'), name = pickedAlarm(frame);
  const a = frame.alarms.find((r) => r.line === name);
  box.hidden = !a || S.tab !== 'active';
  if (!a) return;
  box.dataset.line = a.line;
  const clears = a.state === 'active' ? ` (${CLEARS})` : '';
  setText(box.querySelector('.r-head'), `${a.line} · ${a.level} · ${a.condition.replaceAll('_', ' ')}: ${a.message}${clears}`);
  setText(box.querySelector('.r-text'), a.response || '');
  const detail = a.detail && a.detail !== a.message ? a.detail : '';
  setText(box.querySelector('.r-detail'), detail);
  box.querySelector('.r-detail').hidden = !detail;
}

const rowsByLine = new Map();
function setText(node, text) { if (node.textContent !== text) node.textContent = text; }

// A component status (tide, intake, logger, fatigue store, dock, clock, parameters) that left
// OK: listed and acknowledged as a line's alarm, never shelved; from a monitor that publishes
// no alarm state for it (state 'active') it cannot be acknowledged and clears itself.
const CLEARS = 'clears when its condition does';

function makeRow(line, kind) {
  const tr = el('tr', { 'data-line': line, 'data-kind': kind || 'line' });
  for (let k = 0; k < 7; k++) tr.appendChild(el('td'));
  tr.addEventListener('click', (ev) => { if (!ev.target.closest('button')) selectAlarm(line); });
  tr.children[0].className = 'when';
  tr.children[4].className = 'msg-cell';
  tr.children[4].appendChild(el('div'));
  tr.children[6].className = 'actions';
  const b = el('button', { 'data-ack': line, title: `acknowledge ${line}` }, 'Ack');
  b.addEventListener('click', () => acknowledge(line));
  tr.children[6].appendChild(b);
  const sh = el('button', { 'data-shelve': line, title: `shelve ${line}'s alarm (pick the condition and the time above)` }, 'Shelve');
  sh.addEventListener('click', () => pickShelve(line));
  tr.children[6].appendChild(sh);
  if (kind === 'component') {
    sh.hidden = true;
    tr.children[6].appendChild(el('span', { class: 'clears', title: `${line} ${CLEARS} (not acknowledged: the row goes when the status is OK again)` }, 'clears itself'));
  }
  return tr;
}

function renderActive(frame, lost, replay) {
  // Rows are kept per line and updated in place: a button never moves under a click.
  const body = $('alarms').querySelector('tbody');
  const want = new Set(frame.alarms.map((a) => a.line));
  for (const [line, tr] of rowsByLine) if (!want.has(line)) { tr.remove(); rowsByLine.delete(line); }
  frame.alarms.forEach((a, i) => {
    let tr = rowsByLine.get(a.line);
    if (tr && tr.dataset.kind !== (a.kind || 'line')) { tr.remove(); tr = null; }
    if (!tr) { tr = makeRow(a.line, a.kind); rowsByLine.set(a.line, tr); }
    const component = a.kind === 'component';
    tr.dataset.alarmState = a.state;
    tr.className = `lvl-${a.level}`;
    const td = tr.children;
    setText(td[0], clock(a.raised));
    setText(td[1], a.line);
    setText(td[2], a.level);
    setText(td[3], a.condition.replaceAll('_', ' '));
    td[3].title = td[3].textContent;
    const head = a.message + (a.shelved_condition ? ` (${a.shelved_condition.replaceAll('_', ' ')} shelved)` : '')
      + (a.consequences && a.consequences.length ? ` · consequences (suppressed by design): ${a.consequences.join(', ')}` : '');
    setText(td[4].firstChild, head);
    td[4].firstChild.title = head;  // one line in the list: the whole headline below and here
    tr.classList.toggle('picked', a.line === pickedAlarm(frame));
    tr.dataset.firstOut = a.first_out ? 'true' : 'false';
    tr.dataset.chattering = a.chattering ? 'true' : 'false';
    td[5].textContent = a.state.replace('-', ' ');
    if (a.chattering) td[5].appendChild(el('span', { class: 'chatter', title: 'chattering: many level changes in a short time (ISA-18.2)' }, 'chattering'));
    if (a.first_out) td[5].appendChild(el('span', { class: 'first-out', title: 'the first alarm of the flood' }, 'FIRST OUT'));
    td[5].title = a.state === 'acknowledged' && a.acknowledged_by ? `by ${a.acknowledged_by} at ${clock(a.acknowledged_at)}` : '';
    const clears = a.state === 'active';  // a component of a monitor that does not acknowledge it
    if (clears) td[5].title = `active: ${CLEARS}`;
    if (component) td[6].querySelector('.clears').hidden = !clears;
    const b = td[6].firstChild;
    b.hidden = clears || a.state === 'acknowledged';
    b.disabled = replay || lost || !canAct();
    td[6].children[1].disabled = replay || lost || !canAct();
    if (body.children[i] !== tr) body.insertBefore(tr, body.children[i] || null);
  });
  $('n-active').textContent = `(${frame.alarms.length})`;
  renderResponse(frame, lost);
  $('ack-all').disabled = replay || lost || !canAct() || !frame.alarms.some((a) => a.state !== 'active' && a.state !== 'acknowledged');
  $('no-alarms').hidden = S.tab !== 'active' || frame.alarms.length > 0;
}

function renderHistory(frame) {
  const hist = $('history').querySelector('tbody');
  hist.textContent = '';
  for (const h of frame.history.slice().reverse()) {
    const tr = el('tr', { 'data-history-line': h.line, class: `lvl-${h.level}` });
    tr.appendChild(el('td', { class: 'when' }, clock(h.time)));
    tr.appendChild(el('td', {}, h.line));
    tr.appendChild(el('td', {}, h.event));
    tr.appendChild(el('td', {}, h.level));
    const msg = el('td', { class: 'msg-cell', title: h.message });
    msg.appendChild(el('div', {}, `${h.condition.replaceAll('_', ' ')}: ${h.message}`));
    tr.appendChild(msg);
    tr.appendChild(el('td', {}, h.by));
    hist.appendChild(tr);
  }
  $('n-history').textContent = `(${frame.history.length})`;
}

function showTab(tab) {
  S.tab = tab;
  $('tab-active').classList.toggle('on', tab === 'active');
  $('tab-shelved').classList.toggle('on', tab === 'shelved');
  $('tab-history').classList.toggle('on', tab === 'history');
  $('alarms').hidden = tab !== 'active';
  $('shelved').hidden = tab !== 'shelved';
  $('history').hidden = tab !== 'history';
  if (S.frame) renderAlarms(S.frame, isLost(S.frame));
}

async function acknowledge(line) {
  const box = $('ack-error');
  const res = await act('/api/ack', { line });
  if (res.ok) { box.hidden = true; return; }
  let text = `acknowledge failed (${res.status})`;
  try { text += `: ${(await res.json()).error}`; } catch (e) { /* not JSON */ }
  box.textContent = text;
  box.hidden = false;
}

// ---------------------------------------------------------------- shelving
// An operator shelves a nuisance alarm (or one condition of it) for a while: the monitor keeps
// computing and showing it, does not annunciate it, and brings it back unacknowledged if it is
// still active when the shelf ends. The monitor decides (shelve_max, unshelvable_conditions)
// and answers; the page only asks and shows the answer.
const DURATIONS = [[600, '10 min'], [1800, '30 min'], [3600, '1 h'], [7200, '2 h'], [14400, '4 h'], [28800, '8 h']];

function buildShelveForm() {
  const line = $('shelve-line'), cond = $('shelve-condition');
  const keep = [line.value, cond.value];
  line.textContent = '';
  for (const l of S.config.lines) line.appendChild(el('option', { value: l.name }, l.name));
  line.appendChild(el('option', { value: 'sensors' }, 'sensors'));
  cond.textContent = '';
  cond.appendChild(el('option', { value: 'all' }, 'its active conditions'));
  for (const c of S.config.alarm_conditions || []) cond.appendChild(el('option', { value: c, 'data-condition': c }, c.replaceAll('_', ' ')));
  if (keep[0]) line.value = keep[0];
  if (keep[1]) cond.value = keep[1];
  S.shelveRules = null;
}

// The monitor's rules (from its alarms status): durations up to shelve_max, the conditions it
// never shelves marked and disabled.
function updateShelveForm(frame, lost, replay) {
  const f = frame.flood || {};
  const rules = JSON.stringify([f.shelve_max, f.unshelvable]);
  if (rules !== S.shelveRules) {
    S.shelveRules = rules;
    const dur = $('shelve-duration'), keep = dur.value;
    dur.textContent = '';
    const max = f.shelve_max === null || f.shelve_max === undefined ? Infinity : f.shelve_max;
    for (const [s, label] of DURATIONS) if (s <= max) dur.appendChild(el('option', { value: s }, label));
    if (!dur.children.length && max > 0) dur.appendChild(el('option', { value: max }, ago(max)));
    if (keep) dur.value = keep;
    for (const o of $('shelve-condition').options) {
      const never = (f.unshelvable || []).includes(o.value);
      o.disabled = never;
      o.textContent = o.value === 'all' ? 'its active conditions' : o.value.replaceAll('_', ' ') + (never ? ' (never shelved)' : '');
    }
  }
  const off = replay || lost || !canAct() || !$('shelve-duration').children.length;
  for (const id of ['shelve-line', 'shelve-condition', 'shelve-duration', 'shelve-go']) $(id).disabled = off;
  // The monitor's newest answer, unless the frame predates our own request's (the count then
  // still reads as it did before our request, and its answer is an older one).
  const n = f.shelve_requests;
  if (f.shelve_answer && n !== S.shelveSeen && n !== S.shelveBefore && !S.shelvePending) {
    S.shelveSeen = f.shelve_requests;
    showShelveAnswer(f.shelve_answer);
  }
}

function pickShelve(line) {
  $('shelve-line').value = line;
  const row = (S.frame && S.frame.alarms || []).find((a) => a.line === line);
  const c = row && row.condition && !['none', 'stale'].includes(row.condition) ? row.condition : 'all';
  $('shelve-condition').value = c;
  $('shelve-go').focus();
}

function showShelveAnswer(text, refused) {
  const box = $('shelve-answer');
  box.textContent = text;
  box.classList.toggle('refused', !!refused || text.includes(': refused: '));
}

async function shelve(line, condition, seconds) {
  S.shelvePending = true;
  showShelveAnswer(seconds ? `shelving ${line}…` : `unshelving ${line}…`);
  try {
    const res = await act('/api/shelve', { line, condition, seconds });
    let body = {};
    try { body = await res.json(); } catch (e) { /* not JSON */ }
    if (res.ok) showShelveAnswer(body.answer || `sent (${body.sent}); no answer from the monitor yet`);
    else showShelveAnswer(`${seconds ? 'shelve' : 'unshelve'} refused (${res.status}): ${body.error || ''}`, true);
    if (S.frame && S.frame.flood) {
      S.shelveBefore = S.frame.flood.shelve_requests;
      S.shelveSeen = S.shelveBefore + (res.ok ? 1 : 0);
    }
  } finally { S.shelvePending = false; }
}

function makeShelvedRow(r) {
  const tr = el('tr', { 'data-shelved-line': r.line, 'data-shelved-condition': r.condition });
  for (let k = 0; k < 7; k++) tr.appendChild(el('td'));
  tr.children[0].className = 'when';
  tr.children[4].className = 'msg-cell';
  tr.children[4].appendChild(el('div'));
  tr.children[6].className = 'actions';
  const b = el('button', { 'data-unshelve': r.line, title: `unshelve ${r.line} now` }, 'Unshelve');
  b.addEventListener('click', () => shelve(r.line, 'all', 0));
  tr.children[6].appendChild(b);
  return tr;
}

function renderShelved(frame, lost, replay) {
  // Rows are kept per line and condition and updated in place, as the active list's: the
  // messages change every frame, and a rebuilt row would take the Unshelve button from under
  // a click.
  const body = $('shelved').querySelector('tbody');
  const want = frame.shelved || [];
  const keyOf = (line, condition) => `${line}\u0000${condition}`;
  const have = new Map([...body.children].map((tr) => [keyOf(tr.dataset.shelvedLine, tr.dataset.shelvedCondition), tr]));
  const wanted = new Set(want.map((r) => keyOf(r.line, r.condition)));
  for (const [key, tr] of have) if (!wanted.has(key)) { tr.remove(); have.delete(key); }
  want.forEach((r, i) => {
    const tr = have.get(keyOf(r.line, r.condition)) || makeShelvedRow(r);
    tr.className = `lvl-${r.level}`;
    const td = tr.children;
    setText(td[0], clock(r.until));
    td[0].title = `until ${clock(r.until, true)}`;
    setText(td[1], r.line);
    setText(td[2], r.condition === 'all' ? 'whole alarm' : r.condition.replaceAll('_', ' '));
    td[3].textContent = r.level;
    if (r.chattering) td[3].appendChild(el('span', { class: 'chatter' }, 'chattering'));
    setText(td[4].firstChild, r.message);
    td[4].title = r.message;
    setText(td[5], r.by);
    td[6].firstChild.disabled = replay || lost || !canAct();
    if (body.children[i] !== tr) body.insertBefore(tr, body.children[i] || null);
  });
  $('n-shelved').textContent = `(${want.length})`;
  $('no-shelved').hidden = S.tab !== 'shelved' || want.length > 0;
}

// ---------------------------------------------------------------- access: who may act
// The console says how it is served (config.access): 'open' (this PC's page acts), 'token'
// (operators sign in with their token: every action carries "Authorization: Bearer TOKEN"; the
// page is read-only until then) or 'read-only'. The token stays in this tab (sessionStorage):
// never in the URL, a cookie or a log.
const TOKEN_KEY = 'catenary-console-token';

function canAct() {
  const c = S.config;
  return !!c && c.mode === 'live' && c.access !== 'read-only' && (c.access !== 'token' || !!S.operator);
}

// Every state-changing request goes through here (a POST of JSON, with the token if any).
// (`token`: one being tried, signing in.)
function act(path, body, token) {
  return cmLink.post(path, body, TOKEN_KEY, signedOut, token);
}

// The stored token was refused (and forgotten): nobody is signed in any more.
function signedOut() {
  setOperator(null);
}

function setOperator(name) {
  S.operator = name;
  const b = $('operator');
  const c = S.config;
  document.body.dataset.access = c.access;
  document.body.dataset.operator = name || '';
  b.hidden = c.mode !== 'live' || c.access === 'open';
  b.disabled = c.access === 'read-only';
  b.classList.toggle('signed', !!name);
  b.textContent = c.access === 'read-only' ? 'read-only console' : (name ? `${name} · sign out` : 'read-only: sign in');
  b.title = name ? `operator ${name} acknowledges from this page: click to sign out` : 'operators sign in with their token to acknowledge';
  if (!canAct()) $('ack-all').disabled = true;
  if (S.frame) renderAlarms(S.frame, isLost(S.frame));
}

async function signIn(ev) {
  ev.preventDefault();
  const token = $('token').value.trim();
  $('token').value = '';
  const res = await act('/api/operator', {}, token);
  if (!res.ok) {
    let text = res.status === 401 ? 'sign-in refused: not an operator token of this console' : `sign-in refused (${res.status})`;
    if (res.status !== 401) try { text += `: ${(await res.json()).error}`; } catch (e) { /* not JSON */ }
    $('signin-error').textContent = text;
    return;
  }
  sessionStorage.setItem(TOKEN_KEY, token);
  $('signin').hidden = true;
  $('signin-error').textContent = '';
  setOperator((await res.json()).operator);
  restartStream();
}

function bindAccess() {
  $('operator').addEventListener('click', () => {
    if (S.operator) { sessionStorage.removeItem(TOKEN_KEY); setOperator(null); return; }
    $('signin').hidden = false;
    $('token').focus();
  });
  $('signin').addEventListener('submit', signIn);
  $('signin-cancel').addEventListener('click', () => { $('signin').hidden = true; $('signin-error').textContent = ''; });
  setOperator(null);
  if (S.config.access === 'token' && sessionStorage.getItem(TOKEN_KEY)) {
    act('/api/operator', {}).then(async (res) => { if (res.ok) setOperator((await res.json()).operator); });
  }
}

// ---------------------------------------------------------------- tide
function renderTide(frame, lost) {
  const t = frame.tide;
  const box = $('tide');
  const arrow = { rising: '↑ rising', falling: '↓ falling', steady: '→ steady', unknown: 'trend not known yet (needs half the trend window of depth)' }[t.trend || 'unknown'];
  const rate = t.rate_m_per_h === null || t.rate_m_per_h === undefined ? '' : ` ${t.rate_m_per_h >= 0 ? '+' : ''}${t.rate_m_per_h.toFixed(2)} m/h`;
  box.innerHTML = '';
  box.appendChild(el('div', { class: 'tide-big' }, t.depth === null ? '— m' : `${t.depth.toFixed(2)} m`));
  box.appendChild(el('div', { class: 'tide-trend' }, `${arrow}${rate}`));
  box.appendChild(el('div', { class: `badge ${lost ? 'STALE' : t.level}` }, `${lost ? 'STALE' : t.level}: ${t.message}`));
  for (const st of frame.monitor || []) {
    // The monitor's own health: quiet while OK, a coloured badge otherwise.
    const cls = st.level === 'OK' ? 'muted' : `badge ${st.level}`;
    box.appendChild(el('div', { class: cls, 'data-monitor-status': st.name, 'data-level': st.level },
      `${st.name}: ${st.level} ${st.message}`));
  }
}

// ---------------------------------------------------------------- trend
function buildPickers() {
  const pick = $('trend-line');
  pick.textContent = '';
  for (const line of S.config.lines) pick.appendChild(el('option', { value: line.name }, line.name));
  if (S.line) pick.value = S.line;
}

function bindPickers() {
  const pick = $('trend-line');
  pick.addEventListener('change', () => selectLine(pick.value));
  $('trend-span').addEventListener('change', () => { S.span = parseFloat($('trend-span').value); refreshTrend(); });
}

function selectLine(name) {
  S.line = name;
  $('trend-line').value = name;
  if (S.frame) render(S.frame);
  refreshTrend();
}

async function refreshTrend() {
  if (!S.line) return;
  S.trendAt = performance.now();
  const t = S.config.mode === 'live' ? '' : `&t=${S.replay.t}`;
  try {
    const data = await (await fetch(`/api/trend?line=${encodeURIComponent(S.line)}&span=${S.span}${t}`)).json();
    drawTrend(data);
  } catch (e) { /* the server is gone: the banner says so */ }
}

function niceRange(values, refs) {
  let lo = Infinity, hi = -Infinity;
  for (const v of values.concat(refs)) if (v !== null && v !== undefined && isFinite(v)) { lo = Math.min(lo, v); hi = Math.max(hi, v); }
  if (!isFinite(lo)) { lo = 0; hi = 1; }
  if (hi - lo < 1e-9) { hi += 1; lo -= 1; }
  const pad = (hi - lo) * 0.08;
  return [lo - pad, hi + pad];
}

function drawTrend(data) {
  const box = $('trend');
  const W = box.clientWidth || 1000, H = box.clientHeight || 240;
  box.setAttribute('viewBox', `0 0 ${W} ${H}`);
  box.textContent = '';
  const cfg = S.config.lines.find((l) => l.name === data.line) || {};
  const s = data.series || {}, d = data.depth || {};
  const warnT = cfg.mbl ? cfg.mbl / S.config.safety_factor_warn * KN : null;
  const panels = [
    { label: `${data.line} tension kN`, cls: 's-tension', t: s.t, v: (s.tension_max || []).map((x) => x === null ? null : x * KN), refs: [], warn: warnT },
    { label: 'uplift kN', cls: 's-uplift', t: s.t, v: (s.uplift_max || []).map((x) => x === null ? null : x * KN), refs: [0], warn: cfg.allowed_uplift ? cfg.allowed_uplift * KN : null },
    { label: 'anchor margin m', cls: 's-margin', t: s.t, v: s.margin_min || [], refs: [0, S.config.anchor_margin_warn], warn: S.config.anchor_margin_warn, zero: true },
    { label: 'depth m', cls: 's-depth', t: d.t, v: d.depth_max || [], refs: [] },
  ];
  const left = 62, right = 8, gap = 6, ph = (H - 18 - gap * 3) / 4;
  // A console younger than the span: the axis starts at the first sample (the label says so).
  const first = Math.min(...[s.t, d.t].filter((a) => a && a.length).map((a) => a[0]));
  if (isFinite(first) && first > data.lo) data.lo = Math.max(data.lo, first - 0.02 * (data.hi - first));
  const x = (t) => left + (W - left - right) * (t - data.lo) / Math.max(data.hi - data.lo, 1e-9);
  panels.forEach((p, i) => {
    const top = i * (ph + gap);
    const vis = p.warn !== null && p.warn !== undefined && p.v.some((v) => v !== null && v > 0.6 * p.warn) ? [p.warn] : [];
    const [lo, hi] = niceRange(p.v.filter((v, k) => p.t && p.t[k] >= data.lo), p.refs.concat(vis));
    const y = (v) => top + ph - ph * (v - lo) / (hi - lo);
    box.appendChild(svg('rect', { x: left, y: top, width: W - left - right, height: ph, fill: '#22272c' }));
    box.appendChild(svg('text', { x: left + 6, y: top + 13 }, p.label));
    box.appendChild(svg('text', { x: left - 4, y: top + 10, 'text-anchor': 'end' }, hi.toPrecision(4)));
    box.appendChild(svg('text', { x: left - 4, y: top + ph, 'text-anchor': 'end' }, lo.toPrecision(4)));
    if (p.warn !== null && p.warn !== undefined) {
      if (p.warn >= lo && p.warn <= hi) box.appendChild(svg('line', { class: 'ref', x1: left, x2: W - right, y1: y(p.warn), y2: y(p.warn) }));
      else box.appendChild(svg('text', { x: W - right - 4, y: top + 13, 'text-anchor': 'end', class: 'muted' }, `warning ${p.warn.toFixed(0)} (off scale)`));
    }
    if (p.zero && lo < 0 && hi > 0) box.appendChild(svg('line', { class: 'ref zero', x1: left, x2: W - right, y1: y(0), y2: y(0) }));
    let path = '', pen = false;
    (p.t || []).forEach((t, k) => {
      const v = p.v[k];
      if (v === null || v === undefined) { pen = false; return; }
      path += `${pen ? 'L' : 'M'}${x(t).toFixed(1)} ${y(v).toFixed(1)} `;
      pen = true;
    });
    if (path) box.appendChild(svg('path', { class: `series ${p.cls}`, d: path }));
  });
  const bottom = 4 * ph + 3 * gap + 14;
  for (let k = 0; k <= 6; k++) {
    const t = data.lo + (data.hi - data.lo) * k / 6;
    box.appendChild(svg('text', { x: x(t), y: bottom, 'text-anchor': k === 0 ? 'start' : k === 6 ? 'end' : 'middle' }, clock(t)));
  }
}

// ---------------------------------------------------------------- frame, banner, sound
function isLost(frame) { return S.serverLost || frame.connection === 'lost'; }

function render(frame) {
  S.frame = frame;
  if (!sameLines(frame)) reconfigure();
  const lost = isLost(frame);
  for (const view of frame.lines) renderTile(view, lost, frame);
  renderPlan(frame, lost);
  renderAlarms(frame, lost);
  renderTide(frame, lost);
  renderTimes(frame);
  if (S.config.mode !== 'live') $('replay-time').textContent = `log time ${clock(frame.now, true)}`;
  if (S.config.mode === 'live') sound(frame, lost);
  if (S.bench) S.bench.push([performance.timeOrigin + performance.now(), frame.lines.map((l) => l.top_tension)]);
}

// Why the page has no live data and when it tries again (the stream's state).
function streamWords() {
  const st = S.stream;
  const why = st.why || (st.state === 'open' ? 'the stream is silent' : 'no answer yet');
  const left = (st.retryAt - performance.now()) / 1000;
  return st.state === 'retrying' && left > 0 ? `${why}; retrying in ${Math.ceil(left)} s` : `${why}; connecting…`;
}

function renderBanner(frame) {
  const b = $('banner'), pill = $('status-pill');
  let text = null, kind = null;
  if (!frame) {  // nothing received yet
    if (S.serverLost) {
      kind = 'lost';
      text = `NO LIVE DATA for ${ago((performance.now() - S.liveStart) / 1000)} since the page opened — ${streamWords()}`;
    }
    if (kind) { b.hidden = false; b.dataset.connection = kind; b.textContent = text; }
    pill.className = `pill ${kind === 'lost' ? 'lost' : 'ok'}`;
    pill.textContent = kind === 'lost' ? 'NO LIVE DATA' : 'connecting…';
    return;
  }
  const silent = frame.silent_s === null || frame.silent_s === undefined ? null : frame.silent_s + sinceFrame();
  if (S.serverLost) {
    kind = 'lost';
    text = `CONSOLE SERVER UNREACHABLE for ${ago(sinceFrame())} — nothing shown is current (last data ${clock(frame.now)}) — ${streamWords()}`;
  } else if (frame.connection === 'lost') {
    kind = 'lost';
    text = frame.snapshot_t === null ? `NO DATA FROM THE MONITOR: nothing on /diagnostics for ${ago(silent)} since the console started` :
      `MONITOR SILENT for ${ago(silent)} (period ${S.config.period_s} s) — values shown are the last received, at ${clock(frame.snapshot_t)}`;
  } else if (frame.connection === 'waiting') {
    kind = 'waiting';
    text = 'waiting for the monitor on /diagnostics…';
  }
  if (kind) { b.hidden = false; b.dataset.connection = kind; b.textContent = text; } else { b.hidden = true; delete b.dataset.connection; }
  pill.className = `pill ${kind === 'lost' ? 'lost' : 'ok'}`;
  pill.textContent = kind === 'lost' ? 'CONNECTION LOST' : kind === 'waiting' ? 'waiting' : `monitor ok · ${ago(silent)}`;
}

// Live data lost (no frame for SERVER_TIMEOUT_S, or none since the page opened): banner,
// STALE tiles and the loss-of-monitoring tone, repeated while it lasts.
function watchdog() {
  if (S.config && S.config.mode !== 'live') return;
  const since = S.lastMessage || S.liveStart;
  const lost = (performance.now() - since) / 1000 > SERVER_TIMEOUT_S;
  if (lost !== S.serverLost) {
    S.serverLost = lost;
    if (S.frame) render(S.frame); else if (lost) sound(NO_FRAME, true);
  } else if (lost) sound(S.frame || NO_FRAME, true); // no frames come while the server is gone
  if (S.frame) renderTimes(S.frame); else renderBanner(null);
  updateSoundButton();
}

function unlockAudio() {
  if (S.audio) return;
  try { S.audio = new (window.AudioContext || window.webkitAudioContext)(); } catch (e) { S.audio = null; }
  updateSoundButton();
}

function soundButton(ev) {
  ev.stopPropagation();
  if (!S.audio || S.audio.state !== 'running') { unlockAudio(); if (S.audio) S.audio.resume(); updateSoundButton(); return; }
  S.mutedUntil = performance.now() + SILENCE_S * 1000;
  updateSoundButton();
}

function updateSoundButton() {
  const b = $('sound');
  const left = (S.mutedUntil - performance.now()) / 1000;
  if (!S.audio || S.audio.state !== 'running') { b.textContent = 'sound off: click to enable'; b.className = 'sound'; }
  else if (left > 0) { b.textContent = `silenced ${Math.ceil(left)} s`; b.className = 'sound muted'; }
  else { b.textContent = `sound on (silence ${SILENCE_S} s)`; b.className = 'sound on'; }
}

// Beeps for each new unacknowledged ERROR (a component status's too), each component status
// newly at ERROR from a monitor that does not acknowledge it (active: it beeps until it clears)
// and for the loss of monitoring itself
// (the monitor silent or the console server unreachable: an alarm of its own), again every
// REPEAT_S; silence mutes all of it for SILENCE_S.
function sound(frame, lost) {
  const errors = frame.alarms.filter((a) => a.level === 'ERROR'
    && (a.state === 'unacknowledged' || (a.kind === 'component' && a.state === 'active')));
  const keys = new Set(errors.map((a) => `${a.line}@${a.raised}`));
  if (lost) keys.add('monitoring lost');
  const fresh = [...keys].some((k) => !S.knownErrors.has(k));
  S.knownErrors = keys;
  const now = performance.now();
  if (!keys.size || now < S.mutedUntil) return;
  if (fresh || now - S.lastBeep > REPEAT_S * 1000) beep();
}

function beep() {
  S.lastBeep = performance.now();
  S.beeps += 1;
  const ctx = S.audio;
  if (!ctx || ctx.state !== 'running') return;
  for (let k = 0; k < 3; k++) {
    const osc = ctx.createOscillator(), gain = ctx.createGain();
    osc.frequency.value = k % 2 ? 660 : 880;
    gain.gain.value = 0.15;
    osc.connect(gain).connect(ctx.destination);
    osc.start(ctx.currentTime + k * 0.22);
    osc.stop(ctx.currentTime + k * 0.22 + 0.18);
  }
}

document.addEventListener('DOMContentLoaded', start);

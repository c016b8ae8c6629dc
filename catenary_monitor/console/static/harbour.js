// catenary_monitor harbour page: every dock's tile, the map and the harbour-wide alarm list,
// from GET /api/config once and GET /api/stream (server_link.js: Server-Sent Events read with
// fetch, retried with backoff). The page decides nothing: levels, ages and alarms come from
// the server.
'use strict';

const TOKEN_KEY = 'catenary-harbour-token';
const S = { config: null, frame: null, last: 0, why: '', operator: null };
const $ = (id) => document.getElementById(id);

function el(tag, cls, text) {
  const e = document.createElement(tag);
  if (cls) e.className = cls;
  if (text !== undefined && text !== null) e.textContent = String(text);
  return e;
}

const kN = (n) => (n === null || n === undefined ? '—' : `${(n / 1000).toFixed(1)} kN`);
const metres = (m) => (m === null || m === undefined ? '—' : `${m.toFixed(2)} m`);

function duration(s) {
  if (s < 90) return `${s.toFixed(0)} s`;
  if (s < 5400) return `${(s / 60).toFixed(0)} min`;
  return `${(s / 3600).toFixed(1)} h`;
}

function age(s) {
  if (s === null || s === undefined) return 'none yet';
  return s < 10 ? `${s.toFixed(1)} s ago` : `${duration(s)} ago`;
}

// The dock's time to uplift: the nearest forecast, "lifted now", "not coming" or unknown.
function timeToUplift(dock) {
  const states = dock.lines.map((l) => l.time_to_uplift_state);
  if (dock.time_to_uplift !== null && dock.time_to_uplift !== undefined) {
    if (dock.time_to_uplift <= 0) return ['lifted now', true];
    return [`${duration(dock.time_to_uplift)} (${dock.time_to_uplift_line})`, true];
  }
  if (states.length && states.every((s) => s === 'not coming')) return ['not coming', false];
  return ['unknown', false];
}

function row(dl, label, value, bad) {
  dl.appendChild(el('dt', '', label));
  dl.appendChild(el('dd', bad ? 'bad' : '', value));
}

function tile(dock) {
  const t = el('article', `tile lv-${dock.level}`);
  t.dataset.dock = dock.name;
  t.dataset.level = dock.level;
  t.dataset.alive = String(dock.monitor_alive);
  const head = el('div', 'head');
  const name = el('div', 'name');
  if (dock.console_url) {
    const a = el('a', '', dock.name);
    a.href = dock.console_url;
    a.target = '_blank';
    a.rel = 'noopener noreferrer';
    a.title = `open ${dock.name}'s console`;
    name.appendChild(a);
  } else {
    name.textContent = dock.name;
  }
  head.appendChild(name);
  head.appendChild(el('span', 'muted', `domain ${dock.domain_id}`));
  head.appendChild(el('span', `level lv-${dock.level}`, dock.level));
  t.appendChild(head);
  if (!dock.monitor_alive) {
    const last = dock.last_level ? ` (last ${dock.last_level})` : '';
    t.appendChild(el('div', 'silent', dock.status_age_s === null ? 'NO DATA FROM ITS MONITOR'
      : `MONITOR SILENT${last}`));
  } else if (dock.monitors && dock.monitors.length > 1) {
    t.appendChild(el('div', 'silent', `${dock.monitors.length} MONITORS IN ONE DOMAIN`));
  }
  t.appendChild(el('div', 'msg', dock.message));
  const dl = el('dl');
  const inAlarm = dock.lines_in_alarm;
  row(dl, 'lines in alarm', inAlarm.length ? `${inAlarm.length}: ${inAlarm.join(', ')}` : 'none',
    inAlarm.length > 0);
  const upl = dock.worst_uplift_force;
  row(dl, 'worst uplift', upl === null ? '—' : `${kN(upl)} (${dock.worst_uplift_line})`, upl > 0);
  const mar = dock.worst_anchor_margin;
  row(dl, 'anchor margin', mar === null ? '—' : `${metres(mar)} (${dock.worst_anchor_margin_line})`,
    mar !== null && mar < 0);
  const [ttu, near] = timeToUplift(dock);
  row(dl, 'time to uplift', ttu, near);
  row(dl, 'monitor', dock.monitor_alive ? 'alive' : 'NOT ALIVE', !dock.monitor_alive);
  row(dl, 'newest status', age(dock.status_age_s), !dock.monitor_alive);
  t.appendChild(dl);
  if (dock.kpis) t.appendChild(kpiLine(dock.kpis));
  return t;
}

// The fleet's newest day of the dock (--fleet-dataset): alarms per 10 min, time in alarm,
// the accumulated fatigue of its worst line.
function kpiLine(kpis) {
  const box = el('div', 'kpis');
  box.dataset.kpis = '';
  if (!Array.isArray(kpis)) {
    box.textContent = `fleet: ${kpis.error}`;
    return box;
  }
  if (!kpis.length) {
    box.textContent = 'fleet: no day of this dock in the dataset';
    return box;
  }
  const k = kpis[kpis.length - 1];
  const rate = k.alarms_per_10min === null ? '—' : k.alarms_per_10min.toFixed(2);
  const fatigue = k.fatigue === null ? '—' : `${k.fatigue.toExponential(2)} (${k.fatigue_line})`;
  box.textContent = `fleet ${k.day}: ${rate} alarms/10 min, ${duration(k.time_in_alarm_s)} in `
    + `alarm, fatigue ${fatigue}`;
  return box;
}

function renderTiles(frame) {
  const box = $('tiles');
  box.replaceChildren(...frame.docks.map(tile));
}

function renderCounts(frame) {
  const box = $('counts');
  box.replaceChildren(...['ERROR', 'STALE', 'WARN', 'OK'].map((lv) => {
    const n = frame.counts[lv] || 0;
    return el('span', `chip lv-${lv}${n ? '' : ' none'}`, `${n} ${lv}`);
  }));
}

// North up, east right: an equirectangular projection around the docks' mean latitude.
function renderMap(frame) {
  const placed = frame.docks.filter((d) => d.position);
  $('map-panel').hidden = placed.length === 0;
  $('grid').classList.toggle('nomap', placed.length === 0);
  if (!placed.length) return;
  const lat0 = placed.reduce((a, d) => a + d.position.lat, 0) / placed.length;
  const k = Math.cos((lat0 * Math.PI) / 180);
  const xs = placed.map((d) => d.position.lon * k), ys = placed.map((d) => -d.position.lat);
  const [x0, x1, y0, y1] = [Math.min(...xs), Math.max(...xs), Math.min(...ys), Math.max(...ys)];
  const span = Math.max(x1 - x0, (y1 - y0) * (4 / 3), 1e-9);
  const scale = 240 / span;  // room for the labels at the edges
  const svg = $('map');
  const ns = 'http://www.w3.org/2000/svg';
  const items = [];
  placed.forEach((d, i) => {
    const x = 200 + (xs[i] - (x0 + x1) / 2) * scale;
    const y = 150 + (ys[i] - (y0 + y1) / 2) * scale;
    const g = document.createElementNS(ns, 'g');
    g.setAttribute('data-dock', d.name);
    const c = document.createElementNS(ns, 'circle');
    c.setAttribute('cx', x.toFixed(1));
    c.setAttribute('cy', y.toFixed(1));
    c.setAttribute('r', d.level === 'OK' ? '8' : '11');
    const colour = { OK: '#3fa45b', WARN: '#e6a700', ERROR: '#e03131', STALE: '#8a8fd0' };
    c.setAttribute('fill', colour[d.level] || '#8a8fd0');
    c.setAttribute('stroke', '#e4e7ea');
    const title = document.createElementNS(ns, 'title');
    title.textContent = `${d.name}: ${d.level}`;
    c.appendChild(title);
    const label = document.createElementNS(ns, 'text');
    const right = x > 200;  // a label toward the middle: never past the map's edge
    label.setAttribute('text-anchor', right ? 'end' : 'start');
    label.setAttribute('x', (right ? x - 14 : x + 14).toFixed(1));
    label.setAttribute('y', (y + 4).toFixed(1));
    label.textContent = d.name;
    g.appendChild(c);
    g.appendChild(label);
    items.push(g);
  });
  svg.replaceChildren(...items);
}

function alarmRow(r) {
  const silent = !r.line;  // the dock itself: its monitor silent, or several mixed
  const box = el('div', `alarm st-${r.state.replace(/ /g, '-')}${silent ? ' silent' : ''}`);
  box.dataset.dock = r.dock;
  const where = el('span', 'where', r.line ? `${r.dock} · ${r.line}` : r.dock);
  if (r.first_out) where.appendChild(el('span', 'first', 'FIRST OUT'));
  box.appendChild(where);
  box.appendChild(el('span', `chip lv-${r.level}`, r.level));
  const state = el('span', 'state', r.state);
  if (S.operator && !silent && r.state !== 'acknowledged' && r.state !== 'active') {
    const b = el('button', '', 'acknowledge');
    b.addEventListener('click', () => acknowledge(r.dock, r.line));
    state.appendChild(document.createTextNode(' '));
    state.appendChild(b);
  }
  box.appendChild(state);
  box.appendChild(el('div', 'msg', r.message));
  return box;
}

function renderAlarms(frame) {
  const rows = frame.alarms;
  $('n-alarms').textContent = rows.length ? `(${rows.length})` : '';
  $('alarms').replaceChildren(...(rows.length ? rows.map(alarmRow)
    : [el('div', 'empty', 'no active alarm in the harbour')]));
}

function render(frame) {
  S.frame = frame;
  renderCounts(frame);
  renderTiles(frame);
  renderMap(frame);
  renderAlarms(frame);
  document.body.dataset.level = frame.level;
  tick();
}

// ---------------------------------------------------------------- the connection
function tick() {
  $('clock').textContent = new Date().toLocaleTimeString();
  const lost = !S.frame || (performance.now() - S.last) / 1000 > cmLink.SILENT_S;
  const pill = $('status-pill');
  pill.textContent = lost ? 'no data' : 'live';
  pill.className = `pill ${lost ? 'lost' : 'ok'}`;
  const banner = $('banner');
  banner.hidden = !lost || !S.config;
  banner.dataset.connection = lost ? 'lost' : 'ok';
  banner.textContent = lost
    ? `NO DATA FROM THE HARBOUR SERVER: the tiles are not live${S.why ? ` (${S.why})` : ''}`
    : '';
}

const pause = (delay) => cmLink.sleep(cmLink.jitter(delay));
const why = (text) => { S.why = text; };

// One frame of the stream: rendered, the server heard.
function liveFrame(frame) {
  S.last = performance.now();
  S.why = '';
  render(frame);
}

async function startLive() {
  for (let delay = cmLink.RETRY_MIN_S; ; delay = cmLink.next(delay)) {
    const ctrl = new AbortController();
    let frames = 0;
    try {
      const reader = await cmLink.open(TOKEN_KEY, ctrl.signal, signedOut);
      S.last = performance.now();
      frames = await cmLink.read(reader, ctrl, liveFrame, why);
      S.why = 'the stream ended';
    } catch (e) {
      if (!ctrl.signal.aborted) S.why = e && e.message ? e.message : String(e);
    }
    if (frames > 0) delay = cmLink.RETRY_MIN_S;
    await pause(delay);
  }
}

// ---------------------------------------------------------------- access (a token harbour)
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
  b.hidden = S.config.access !== 'token';
  b.textContent = name ? `${name}: sign out` : 'read-only: sign in';
  b.classList.toggle('signed', !!name);
  $('access').textContent = S.config.access === 'token'
    ? (name ? `${name} may acknowledge` : 'read-only until an operator signs in') : 'read-only';
  if (S.frame) render(S.frame);
}

async function acknowledge(dock, line) {
  const res = await act('/api/ack', { dock, line });
  if (!res.ok) {
    let why = '';
    try { why = (await res.json()).error; } catch (e) { /* not JSON */ }
    S.why = `acknowledgement refused (${res.status}${why ? `: ${why}` : ''})`;
  }
}

function wireSignin() {
  const form = $('signin');
  $('operator').addEventListener('click', () => {
    if (S.operator) { sessionStorage.removeItem(TOKEN_KEY); setOperator(null); return; }
    form.hidden = false;
    $('token').focus();
  });
  $('signin-cancel').addEventListener('click', () => { form.hidden = true; });
  form.addEventListener('submit', async (ev) => {
    ev.preventDefault();
    const token = $('token').value.trim();
    const res = await act('/api/operator', {}, token);
    if (!res.ok) { $('signin-error').textContent = `refused (${res.status})`; return; }
    sessionStorage.setItem(TOKEN_KEY, token);
    $('token').value = '';
    $('signin-error').textContent = '';
    form.hidden = true;
    setOperator((await res.json()).operator);
  });
}

async function main() {
  setInterval(tick, 500);
  S.config = await cmLink.config('harbour', why, pause);
  document.title = `harbour · ${S.config.docks.length} docks · ${S.config.host}`;
  wireSignin();
  setOperator(null);
  if (S.config.access === 'token' && sessionStorage.getItem(TOKEN_KEY)) {
    const res = await act('/api/operator', {});
    if (res.ok) setOperator((await res.json()).operator);
  }
  startLive();
}

main();

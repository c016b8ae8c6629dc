// catenary_monitor's pages (the console, the harbour): how both talk to their server. GET
// /api/config is asked again with backoff until the server answers; GET /api/stream is read
// with fetch, not EventSource, so the operator's token goes along and every failure is seen
// and retried (a refusal, a cut, a silent stream; EventSource never retries after a non-200
// answer); a request that changes something is a POST of JSON with the token. Loaded before
// the page's own script; each page keeps its own state, token and retry loop.
'use strict';

const cmLink = Object.freeze({
  RETRY_MIN_S: 0.5,  // the retries: doubling from here ...
  RETRY_MAX_S: 8,    // ... to here, each jittered by a quarter
  SILENT_S: 5,       // an open stream without a frame this long is cut and retried

  // The delay after `delay` (s): doubled, at most RETRY_MAX_S.
  next(delay) {
    return Math.min(delay * 2, this.RETRY_MAX_S);
  },

  // `delay` s give or take a quarter, so that many pages do not retry in step.
  jitter(delay) {
    return delay * (0.75 + 0.5 * Math.random());
  },

  sleep(seconds) {
    return new Promise((resolve) => setTimeout(resolve, seconds * 1000));
  },

  // The page's configuration from `server` ("console", "harbour"), asked until it answers:
  // `why(text)` is told each failure, `pause(delay)` waits before the next try.
  async config(server, why, pause) {
    for (let delay = this.RETRY_MIN_S; ; delay = this.next(delay)) {
      try {
        const res = await fetch('/api/config', { cache: 'no-store' });
        if (res.ok) return await res.json();
        why(`the ${server} server answered ${res.status}`);
      } catch (e) { why(`the ${server} server does not answer`); }
      await pause(delay);
    }
  },

  // Opens GET /api/stream with the operator's token (kept under `key` in sessionStorage, if
  // any) and returns its reader; a refused token is forgotten and `signedOut()` called; any
  // refusal throws, naming it.
  async open(key, signal, signedOut) {
    const token = sessionStorage.getItem(key);
    const headers = { Accept: 'text/event-stream' };
    if (token) headers.Authorization = `Bearer ${token}`;
    const res = await fetch('/api/stream', { headers, cache: 'no-store', signal });
    if (res.status === 401 && token) { sessionStorage.removeItem(key); signedOut(); }
    if (!res.ok || !res.body) {
      let why = '';
      try { why = (await res.json()).error; } catch (e) { /* not JSON */ }
      throw new Error(`the stream was refused (${res.status}${why ? `: ${why}` : ''})`);
    }
    return res.body.getReader();
  },

  // Calls `onFrame(frame)` for each event of the open stream `reader` (its `data:` lines, as
  // JSON); cuts it (`ctrl.abort()`, after `onSilent(why)`) when nothing came for SILENT_S.
  // Returns how many frames it carried once it ends.
  async read(reader, ctrl, onFrame, onSilent) {
    const decoder = new TextDecoder();
    let buffer = '', frames = 0, last = performance.now();
    const silent = setInterval(() => {
      if ((performance.now() - last) / 1000 > this.SILENT_S) {
        onSilent(`the stream carried nothing for ${this.SILENT_S} s`);
        ctrl.abort();
      }
    }, 1000);
    try {
      for (;;) {
        const { value, done } = await reader.read();
        if (done) return frames;
        buffer += decoder.decode(value, { stream: true });
        for (let cut = buffer.indexOf('\n\n'); cut >= 0; cut = buffer.indexOf('\n\n')) {
          const data = buffer.slice(0, cut).split('\n').filter((l) => l.startsWith('data:'))
            .map((l) => l.slice(5).replace(/^ /, '')).join('\n');
          buffer = buffer.slice(cut + 2);
          if (!data) continue;
          frames += 1;
          last = performance.now();
          onFrame(JSON.parse(data));
        }
      }
    } finally {
      clearInterval(silent);
    }
  },

  // POSTs `body` as JSON to `path` with the token kept under `key` (sessionStorage), or with
  // `trying`, a token being signed in with. A refused stored token is forgotten and
  // `signedOut()` called; a refused token being tried signs nobody out.
  async post(path, body, key, signedOut, trying) {
    const token = trying || sessionStorage.getItem(key);
    const headers = { 'Content-Type': 'application/json' };
    if (token) headers.Authorization = `Bearer ${token}`;
    const res = await fetch(path, { method: 'POST', headers, body: JSON.stringify(body) });
    if (res.status === 401 && !trying) { sessionStorage.removeItem(key); signedOut(); }
    return res;
  },
});

// The console page's layout problems now, as sentences (empty: none), for the browser tests
// (browser_harness.layout_problems runs it through selenium; arguments[0]: also require every
// tile's level and the alarm list in the window without scrolling):
// text cut by an element that hides its overflow on that axis (or clamps lines; an ellipsis is
// allowed on one line whose title holds the whole text), an element of a
// tile outside its tile, two panels or two tiles overlapping, a panel too small to use or out of the page's
// reach, a bar on top covering a panel, the page wider than the window.
const must = arguments[0], out = [];
window.scrollTo(0, 0);
const W = window.innerWidth, H = window.innerHeight;
const box = (e) => e.getBoundingClientRect();
const shown = (e) => e.getClientRects().length > 0 && getComputedStyle(e).visibility !== 'hidden';
const cross = (a, b) => Math.min(a.right, b.right) - Math.max(a.left, b.left) > 1
  && Math.min(a.bottom, b.bottom) - Math.max(a.top, b.top) > 1;
function name(e) {
  if (e.id) return `#${e.id}`;
  const line = e.closest('[data-line]');
  const cls = typeof e.className === 'string' && e.className.trim() ? `.${e.className.trim().split(/\s+/).join('.')}` : '';
  return `${line ? `${line.dataset.line} ` : ''}${e.tagName.toLowerCase()}${cls}`;
}

const page = document.documentElement;
if (page.scrollWidth > W + 1) out.push(`page ${page.scrollWidth} px wide in a ${W} px window`);
for (const e of document.body.querySelectorAll('*')) {
  if (!shown(e) || e.closest('svg')) continue;
  const cs = getComputedStyle(e);
  // Per axis: an axis that hides (or a line clamp) cuts what overflows it; an axis that scrolls
  // (auto, scroll: the alarm list beyond its height) keeps its content within reach.
  const clamps = cs.webkitLineClamp !== 'none';
  const cutY = (/hidden|clip/.test(cs.overflowY) || clamps) && e.scrollHeight > e.clientHeight + 1;
  const cutX = (/hidden|clip/.test(cs.overflowX) || clamps) && e.scrollWidth > e.clientWidth + 1;
  // A one-line alarm headline may end in an ellipsis: its whole text is its title (and in the
  // selected alarm's box under the list).
  const whole = cutX && !cutY && cs.textOverflow === 'ellipsis' && e.title === e.textContent;
  if (cs.display !== 'inline' && (cutX || cutY) && !whole) {
    out.push(`${name(e)} cuts its content (${e.scrollWidth}x${e.scrollHeight} in `
      + `${e.clientWidth}x${e.clientHeight}): "${e.textContent.trim().slice(0, 60)}"`);
  }
}
const tiles = [...document.querySelectorAll('.tile')];
for (const t of tiles) {
  const r = box(t);
  for (const e of t.querySelectorAll('*')) {
    const b = box(e);
    if (shown(e) && (b.left < r.left - 1 || b.right > r.right + 1 || b.top < r.top - 1 || b.bottom > r.bottom + 1)) {
      out.push(`${name(e)} outside its tile`);
    }
  }
}
const overlaps = (list, what) => list.forEach((a, i) => list.slice(i + 1).forEach((b) => {
  if (cross(box(a), box(b))) out.push(`${what} ${name(a)} and ${name(b)} overlap`);
}));
overlaps(tiles, 'tiles');
const panels = [...document.querySelectorAll('main .panel')];
overlaps(panels, 'panels');
for (const p of panels) {
  const r = box(p);
  if (r.width < 250 || r.height < 150) out.push(`${p.id} too small: ${Math.round(r.width)}x${Math.round(r.height)}`);
  if (r.right > W + 1 || r.bottom + window.scrollY > page.scrollHeight + 1) out.push(`${p.id} out of reach`);
}
for (const id of ['plan', 'trend']) {
  const r = box(document.getElementById(id));
  if (r.height < 140 || r.width < 200) out.push(`#${id} too small: ${Math.round(r.width)}x${Math.round(r.height)}`);
}
for (const bar of document.querySelectorAll('header, #banner, #replay-bar')) {
  if (shown(bar)) panels.forEach((p) => { if (cross(box(bar), box(p))) out.push(`${name(bar)} covers ${p.id}`); });
}
if (must) {
  const inside = (e) => { const b = box(e); return b.top >= 0 && b.bottom <= H && b.left >= 0 && b.right <= W; };
  for (const t of tiles) if (!inside(t.querySelector('.badge'))) out.push(`${t.dataset.line}'s level not in the window`);
  for (const r of document.querySelectorAll('#alarms tr')) if (!inside(r)) out.push(`alarm row ${r.dataset.line || 'head'} not in the window`);
  if (!inside(document.getElementById('ack-all'))) out.push('Acknowledge all not in the window');
}
return out;

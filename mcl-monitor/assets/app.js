// The MCL monitor page (docs/monitor.md). No build step, no library: the
// page reads /api/info, then follows /api/events (a live run) or loads
// /api/records once (a replay), and derives everything it shows from the
// trace records with the rules of docs/monitor.md (*Call states*), the
// same as mcl-monitor/src/state.rs.
'use strict';

const $ = (id) => document.getElementById(id);
const records = [];
let info = { mode: 'live', operator: false, title: '' };
let st = newState();
let applied = 0; // records applied to `st`
let viewT = 0; // replay: the time shown
let finished = false;
let playing = null;
let jumpIndex = -1; // the record a jump went to (highlighted in the log)
const sources = new Map(); // file -> { lines: [div], indents: [n] } or 'loading'
// The state derived from the records applied. `dirty`: the calls whose
// status changed since the last redraw (only their lines and tree nodes are
// updated); `started`: how many calls have run (the chronogram's rows);
// `byLine`, `byMissionLine`: the calls written on each line.
function newState() {
  return { t: 0, calls: new Map(), outcomes: new Map(), summary: null, paused: false,
    poses: new Map(), events: new Set(), missions: new Set(),
    dirty: new Set(), started: 0, posesDirty: false, byLine: new Map(), byMissionLine: new Map() };
}

// Whether the next redraw starts from scratch (a new state: the first, or a
// replay sought backwards).
let full = true;

function index(map, key, c) {
  const l = map.get(key);
  if (l) l.push(c); else map.set(key, [c]);
}

function missionOf(r) { return r.mission || 'mission'; }

function splitSrc(src) {
  const i = src.lastIndexOf(':');
  if (i > 0) {
    const tail = src.slice(i + 1);
    if (/^[0-9]+$/.test(tail)) return [src.slice(0, i), parseInt(tail, 10)];
  }
  return [src, null];
}

function callOf(s, r) {
  if (r.call_site === undefined || r.call_site === null) return null;
  const m = missionOf(r);
  const key = m + '#' + r.call_site;
  let c = s.calls.get(key);
  if (!c) {
    c = { key, mission: m, task: null, label: null, site: r.call_site, file: null, line: null,
      status: 'idle', since: 0, until: null, runs: 0, spans: [] };
    s.calls.set(key, c);
  }
  if (!c.task && r.task) c.task = r.task;
  if (!c.label && r.label) c.label = r.label;
  if (!c.file && r.src) {
    [c.file, c.line] = splitSrc(r.src);
    if (c.line !== null) {
      index(s.byLine, c.file + '\n' + c.line, c);
      index(s.byMissionLine, c.mission + '\n' + c.line, c);
    }
  }
  return c;
}

function endCall(s, c, status, t) {
  if (!c || c.status !== 'running') return;
  s.dirty.add(c);
  c.status = status;
  c.until = t;
  const sp = c.spans[c.spans.length - 1];
  if (sp) { sp.to = t; sp.status = status; }
}

function apply(s, r) {
  s.t = Math.max(s.t, r.t);
  const m = missionOf(r);
  if (m !== '*') s.missions.add(m);
  switch (r.kind) {
    case 'action': {
      const c = callOf(s, r);
      if (!c) break;
      if (r.command === 'disable') endCall(s, c, 'stopped', r.t);
      else if (c.status !== 'running') {
        if (c.runs === 0) s.started += 1;
        s.dirty.add(c);
        c.status = 'running'; c.since = r.t; c.until = null; c.runs += 1;
        c.spans.push({ from: r.t, to: null, status: 'running' });
      }
      break;
    }
    case 'event':
      s.events.add(r.event);
      if (r.ends === 'ok' || r.ends === 'fail') endCall(s, callOf(s, r), r.ends, r.t);
      break;
    case 'fire':
      if (r.ends === 'timeout') endCall(s, callOf(s, r), 'fail', r.t);
      break;
    case 'outcome': s.outcomes.set(m, r.result); break;
    case 'coord_summary': s.summary = r.result; break;
    case 'operator':
      if (r.command === 'pause') s.paused = true;
      else if (r.command === 'resume') s.paused = false;
      break;
    case 'pose': {
      let p = s.poses.get(m);
      if (!p) { p = []; s.poses.set(m, p); }
      p.push([r.x, r.y]);
      s.posesDirty = true;
      break;
    }
    default: break;
  }
}

function outcomeOf(s) {
  // Every mission aborted by the operator: the summary says stuck (state.rs, `json`).
  if (s.summary && s.outcomes.size > 0 && [...s.outcomes.values()].every((r) => r === 'aborted')) return 'aborted';
  if (s.summary) return s.summary;
  if (s.outcomes.size === 1 && s.missions.size <= 1) return [...s.outcomes.values()][0];
  return null;
}

// ---- what the log says about a record

function category(r) {
  switch (r.kind) {
    case 'action': return 'action';
    case 'event': case 'unexpected_event': case 'stale_event': return 'event';
    case 'coord_send': case 'coord_receive': case 'coord_reject': case 'coord_summary': return 'coord';
    case 'operator': return 'operator';
    case 'warning': case 'link': case 'outcome': return 'notice';
    case 'fire': case 'timer': return 'fire';
    default: return 'other';
  }
}

function describe(r) {
  switch (r.kind) {
    case 'action': {
      const p = Object.entries(r.params || {}).map(([k, v]) => k + '=' + JSON.stringify(v)).join(', ');
      return `${r.primitive} ${r.command}(${p})${r.queued ? ' (queued)' : ''}`;
    }
    case 'event': return r.event + (r.ends === 'ok' || r.ends === 'fail' ? ` (ends ${r.ends})` : '');
    case 'fire': return r.transition + (r.ends ? ` (${r.ends})` : '');
    case 'timer': return `${r.transition} until ${r.deadline}`;
    case 'unexpected_event': case 'stale_event': return `${r.event} (${r.reason})`;
    case 'perception': return `${r.name} = ${JSON.stringify(r.value)}`;
    case 'pose': return `x=${r.x.toFixed(1)} y=${r.y.toFixed(1)} z=${r.z.toFixed(1)}`;
    case 'outcome': return `MISSION ${String(r.result).toUpperCase()}${r.reason ? ': ' + r.reason : ''}${r.via ? ' (through ' + r.via + ')' : ''}`;
    case 'coord_send': return `${r.transition} → ${r.to} (#${r.seq})`;
    case 'coord_receive': return `${r.from}/${r.transition} (#${r.seq})`;
    case 'coord_summary': return `ALL MISSIONS ${String(r.result).toUpperCase()}: ${r.messages} messages`;
    case 'operator': return r.command + (r.event ? ' ' + r.event : '');
    default: return r.message || '';
  }
}

function isFailure(r) {
  return (r.kind === 'event' && r.ends === 'fail') ||
    (r.kind === 'fire' && (r.ends === 'timeout' || r.ends === 'catch')) ||
    ((r.kind === 'outcome' || r.kind === 'coord_summary') && r.result !== 'ok') ||
    r.kind === 'unexpected_event' || r.kind === 'coord_reject';
}

function rowClass(r) {
  if (r.kind === 'operator') return 'operator';
  if (isFailure(r)) return 'fail';
  if ((r.kind === 'event' && r.ends === 'ok') || (r.kind === 'outcome' && r.result === 'ok')) return 'ok';
  return '';
}

// ---- the log

function filters() {
  const cats = new Set();
  document.querySelectorAll('#filters input[type=checkbox]').forEach((b) => { if (b.checked) cats.add(b.dataset.cat); });
  return { cats, mission: $('mission-filter').value, text: $('text-filter').value.toLowerCase() };
}

function shown(r, f) {
  if (!f.cats.has(category(r))) return false;
  if (f.mission && missionOf(r) !== f.mission && r.mission !== '*') return false;
  if (f.text) {
    const s = (describe(r) + ' ' + (r.task || '') + ' ' + (r.src || '')).toLowerCase();
    if (!s.includes(f.text)) return false;
  }
  return true;
}

function logRow(r, i) {
  const tr = document.createElement('tr');
  tr.className = rowClass(r) + (i === jumpIndex ? ' current' : '');
  tr.dataset.index = i;
  const where = [r.task ? r.task + (r.label ? ':' + r.label : '') : '', r.src || ''].filter(Boolean).join(' at ');
  for (const text of [r.t.toFixed(3), r.mission || '', r.kind, describe(r), where]) {
    const td = document.createElement('td');
    td.textContent = text;
    tr.appendChild(td);
  }
  return tr;
}

// The log is virtualized: `logIdx` holds the indices of the records that
// pass the filters, and only the rows in view (and a few around) are in
// the page, between two spacers. It follows the end of the run unless
// scrolled up.
const ROW_H = 19;
const logView = { idx: [], top: 0, height: 400, follow: true, drawn: '' };

function renderLog() {
  const f = filters();
  logView.idx = [];
  for (let i = 0; i < applied; i++) if (shown(records[i], f)) logView.idx.push(i);
  // A jump shows its record.
  const k = jumpIndex >= 0 ? logView.idx.indexOf(jumpIndex) : -1;
  if (k >= 0) {
    logView.follow = false;
    logView.top = Math.max(0, k * ROW_H - logView.height / 2);
    logView.scrollTo = logView.top;
  }
  logView.drawn = '';
  drawLog();
}

function appendLog(from) {
  const f = filters();
  const before = logView.idx.length;
  for (let i = from; i < applied; i++) if (shown(records[i], f)) logView.idx.push(i);
  if (logView.idx.length !== before) drawLog();
}

function drawLog() {
  const box = $('log-box');
  const n = logView.idx.length;
  const rows = Math.ceil(logView.height / ROW_H) + 10;
  let first;
  if (logView.follow) first = Math.max(0, n - rows);
  else first = Math.max(0, Math.min(n - rows, Math.floor(logView.top / ROW_H) - 5));
  first = Math.max(0, first);
  const last = Math.min(n, first + rows);
  const key = `${first}:${last}:${n}:${jumpIndex}`;
  if (key === logView.drawn) return;
  logView.drawn = key;
  const body = document.querySelector('#log tbody');
  const frag = document.createDocumentFragment();
  const pad = (h) => {
    const tr = document.createElement('tr');
    tr.className = 'pad';
    const td = document.createElement('td');
    td.colSpan = 5;
    td.style.height = h + 'px';
    tr.appendChild(td);
    return tr;
  };
  frag.appendChild(pad(first * ROW_H));
  for (let k = first; k < last; k++) frag.appendChild(logRow(records[logView.idx[k]], logView.idx[k]));
  frag.appendChild(pad((n - last) * ROW_H));
  body.replaceChildren(frag);
  body.parentElement.dataset.rows = n;
  if (logView.follow) box.scrollTop = n * ROW_H + 1e6;
  else if (logView.scrollTo !== undefined) { box.scrollTop = logView.scrollTo; logView.scrollTo = undefined; }
}

function onLogScroll() {
  const box = $('log-box');
  logView.top = box.scrollTop;
  logView.follow = box.scrollTop + box.clientHeight >= box.scrollHeight - 2 * ROW_H;
  drawLog();
}

// ---- sources

// Long sources are drawn by the browser only where they are in view: their
// lines go in chunks of CHUNK lines whose rendering is skipped off screen
// (`content-visibility: auto`, style.css).
const CHUNK = 100;
const newSources = new Set(); // loaded since the last redraw: marked whole

function loadSource(file) {
  if (sources.has(file)) return;
  sources.set(file, 'loading');
  fetch('/api/source?file=' + encodeURIComponent(file))
    .then((res) => (res.ok ? res.text() : null))
    .then((text) => {
      const box = document.createElement('div');
      box.className = 'file';
      const name = document.createElement('div');
      name.className = 'file-name';
      name.textContent = file;
      box.appendChild(name);
      const lines = [];
      const indents = [];
      let chunk = null;
      (text === null ? ['(source not available)'] : text.split('\n')).forEach((l, k) => {
        if (k % CHUNK === 0) {
          chunk = document.createElement('div');
          chunk.className = 'chunk';
          chunk.style.containIntrinsicSize = 'auto ' + 18 * CHUNK + 'px';
          box.appendChild(chunk);
        }
        const div = document.createElement('div');
        div.className = 'line';
        div.dataset.file = file;
        div.dataset.line = k + 1;
        const no = document.createElement('span');
        no.className = 'no';
        no.textContent = k + 1;
        div.appendChild(no);
        div.appendChild(document.createTextNode(l));
        chunk.appendChild(div);
        lines.push(div);
        indents.push(l.length - l.trimStart().length);
      });
      $('sources').appendChild(box);
      sources.set(file, { lines, indents });
      newSources.add(file);
      schedule();
    })
    .catch(() => sources.delete(file));
}

const RANK = { running: 4, fail: 3, ok: 2, stopped: 1, idle: 0 };

// The status shown for the calls `cs` written on one line: the most
// telling of those that ran.
function markOf(cs) {
  let m = null;
  for (const c of cs || []) if (c.runs > 0 && (!m || RANK[c.status] > RANK[m])) m = c.status;
  return m;
}

function markLine(div, status) {
  const cls = 'line' + (status ? ' ' + status : '');
  if (div && div.className !== cls) div.className = cls;
}

function markFile(file, s) {
  s.lines.forEach((div, k) => markLine(div, markOf(st.byLine.get(file + '\n' + (k + 1)))));
}

// Only the lines of the calls that changed, but for a new state or a
// source just loaded.
function renderSources() {
  if (full) {
    for (const c of st.calls.values()) if (c.file && c.runs > 0) loadSource(c.file);
    for (const [file, s] of sources) if (s !== 'loading') markFile(file, s);
  } else {
    for (const c of st.dirty) {
      if (!c.file || c.line === null) continue;
      loadSource(c.file);
      const s = sources.get(c.file);
      if (s !== 'loading' && !newSources.has(c.file)) markLine(s.lines[c.line - 1], markOf(st.byLine.get(c.file + '\n' + c.line)));
    }
  }
  for (const file of newSources) { const s = sources.get(file); if (s && s !== 'loading') markFile(file, s); }
  newSources.clear();
}

// ---- the control-structure tree (/api/tree), with the calls' states

let trees = [];

function callMarks() {
  const marks = new Map(); // "mission\nline" -> status
  for (const c of st.calls.values()) {
    if (c.runs === 0 || c.line === null) continue;
    const k = c.mission + '\n' + c.line;
    const prev = marks.get(k);
    if (!prev || RANK[c.status] > RANK[prev]) marks.set(k, c.status);
  }
  return marks;
}

function treeNode(mission, part, n, depth, out) {
  const label = part && !/^[0-9]+$/.test(part) ? `<span class="muted">${esc(part)}:</span> ` : '';
  const what = n.kind === 'call' ? esc(n.text) : `<b>${esc(n.kind)}</b>`;
  out.push(`<div class="node" data-mission="${esc(mission)}" data-line="${n.line}" data-kind="${esc(n.kind)}"><span class="st"></span>${'  '.repeat(depth)}${label}${what}  <span class="muted">line ${n.line}</span></div>`);
  for (const [p, c] of n.children) treeNode(mission, p, c, depth + 1, out);
}

// The tree is drawn once; then only the status of the calls that changed
// is written (`treeSpans`: "mission\nline" -> the status elements).
let treeSpans = null;

function markSpan(span, status) {
  const cls = 'st' + (status ? ' ' + status : '');
  if (span.className !== cls) { span.className = cls; span.textContent = status || ''; }
}

function renderTree() {
  if (trees.length === 0) { renderCalls(); return; }
  if (treeSpans === null) {
    const out = [];
    for (const t of trees) {
      out.push(`<div class="node"><b>mission ${esc(t.mission)}</b> <span class="muted">${esc(t.file)}</span></div>`);
      treeNode(t.mission, '', t.root, 1, out);
    }
    $('tree').innerHTML = out.join('');
    treeSpans = new Map();
    for (const n of $('tree').querySelectorAll('.node[data-kind="call"]')) index(treeSpans, n.dataset.mission + '\n' + n.dataset.line, n.firstElementChild);
    full = true;
  }
  const keys = full ? treeSpans.keys() : [...st.dirty].map((c) => c.mission + '\n' + c.line);
  for (const k of keys) {
    const spans = treeSpans.get(k);
    if (!spans) continue;
    const status = markOf(st.byMissionLine.get(k)) || '';
    for (const sp of spans) markSpan(sp, status);
  }
}

// Replaces an element's contents only when they change (a new tree of a
// thousand nodes is a layout of the page).
function setHtml(el, html) {
  if (el.dataset.html !== html) {
    el.innerHTML = html;
    el.dataset.html = html;
  }
}

// Without a tree (a run of a PNML file): the calls in source order,
// indented as written.
function renderCalls() {
  if (!full && st.dirty.size === 0) return;
  const calls = [...st.calls.values()].filter((c) => c.runs > 0);
  calls.sort((a, b) => a.mission.localeCompare(b.mission) || (a.file || '').localeCompare(b.file || '') ||
    (a.line || 0) - (b.line || 0) || a.site - b.site);
  const out = [];
  let mission = null;
  for (const c of calls) {
    if (st.missions.size > 1 && c.mission !== mission) { mission = c.mission; out.push(`<div class="node"><b>${esc(mission)}</b></div>`); }
    const s = sources.get(c.file);
    const indent = s && s !== 'loading' && c.line ? Math.floor((s.indents[c.line - 1] || 0) / 4) : 0;
    const name = esc((c.task || '?') + (c.label ? ':' + c.label : ''));
    out.push(`<div class="node" data-call="${esc(c.key)}"><span class="st ${c.status}">${c.status}</span>${'  '.repeat(indent)}${name}  <span class="muted">line ${c.line ?? '?'}${c.runs > 1 ? ', ' + c.runs + ' runs' : ''}</span></div>`);
  }
  setHtml($('tree'), out.join('') || '<span class="muted">no call has started</span>');
}

function esc(s) {
  return String(s).replace(/[&<>"]/g, (ch) => ({ '&': '&amp;', '<': '&lt;', '>': '&gt;', '"': '&quot;' }[ch]));
}

// ---- chronogram

const COLOR = { running: '#e0a800', ok: '#2e9d3a', fail: '#c0392b', stopped: '#9aa1ad' };

// Widths of the drawing boxes, read once and on resize (reading them while
// drawing would force a layout of the page each time).
const widths = { chrono: 700, map: 600 };

function measure() {
  widths.chrono = Math.max(400, ($('chrono').clientWidth || 700) - 20);
  widths.map = Math.max(400, ($('map-box').clientWidth || 600) - 20);
  chronoView.height = Math.max(120, Math.floor(window.innerHeight * 0.34) - 4);
  logView.height = Math.max(200, $('log-box').clientHeight || 400);
}

// A canvas of the height of its box, showing only the rows in view (the
// box scrolls over a spacer of the height of every row), redrawn at most
// every CHRONO_MS (but when its rows change or it scrolls).
const CHRONO_MS = 100;
const chronoView = { order: [], started: -1, top: 0, height: 300, last: -Infinity };

function renderChrono(now, force) {
  if (chronoView.started !== st.started || full) {
    chronoView.order = [...st.calls.values()].filter((c) => c.runs > 0);
    chronoView.order.sort((a, b) => a.mission.localeCompare(b.mission) || (a.line || 0) - (b.line || 0) || a.site - b.site);
    chronoView.started = st.started;
    force = true;
  }
  const t0 = performance.now();
  if (!force && t0 - chronoView.last < CHRONO_MS) return false;
  chronoView.last = t0;
  const calls = chronoView.order;
  const W = widths.chrono, L = 200, H = 16;
  const total = 22 + calls.length * H;
  const h = Math.min(total, chronoView.height);
  const box = $('chrono');
  let canvas = box.querySelector('canvas');
  if (!canvas) {
    const spacer = document.createElement('div');
    spacer.className = 'spacer';
    canvas = document.createElement('canvas');
    spacer.appendChild(canvas);
    box.appendChild(spacer);
  }
  const spacer = canvas.parentElement;
  if (spacer.style.height !== total + 'px') spacer.style.height = total + 'px';
  if (canvas.width !== W) canvas.width = W;
  if (canvas.height !== h) canvas.height = h;
  const top = Math.max(0, Math.min(chronoView.top, total - h));
  canvas.style.top = top + 'px';
  const g = canvas.getContext('2d');
  g.clearRect(0, 0, W, h);
  const tmax = Math.max(now, 1e-9);
  const x = (t) => L + ((W - L - 10) * Math.min(t, tmax)) / tmax;
  g.font = '11px system-ui, sans-serif';
  const first = Math.max(0, Math.floor((top - 18) / H));
  const last = Math.min(calls.length, Math.ceil((top + h) / H) + 1);
  for (let i = first; i < last; i++) {
    const c = calls[i];
    const y = 18 + i * H - top;
    const name = (st.missions.size > 1 ? c.mission + ' ' : '') + (c.task || '?') + (c.label ? ':' + c.label : '') + ' @' + (c.line ?? '?');
    g.fillStyle = '#1d2330';
    g.fillText(name, 4, y + 11, L - 8);
    for (const sp of c.spans) {
      const to = sp.to === null ? now : sp.to;
      g.fillStyle = COLOR[sp.status];
      g.fillRect(x(sp.from), y + 2, Math.max(1.5, x(to) - x(sp.from)), H - 5);
    }
  }
  g.strokeStyle = '#1d2330';
  g.setLineDash([3, 3]);
  g.beginPath(); g.moveTo(x(now) + 0.5, 0); g.lineTo(x(now) + 0.5, h); g.stroke();
  g.setLineDash([]);
  g.fillStyle = '#6b7280';
  g.font = '10px system-ui, sans-serif';
  g.fillText('0 s', L, 11);
  g.textAlign = 'end';
  g.fillText(now.toFixed(1) + ' s', W - 10, 11);
  g.textAlign = 'start';
  canvas.dataset.rows = calls.length;
  return true;
}

// ---- map

const TRACK = ['#1f6feb', '#c0392b', '#2e9d3a', '#8e44ad', '#d35400', '#16a085', '#7f8c8d', '#b7950b'];

// Redrawn only when a pose came, at most every MAP_MS.
const MAP_MS = 250;
let mapLast = -Infinity;

function renderMap() {
  if (!full && !st.posesDirty) return true;
  const t0 = performance.now();
  if (!full && t0 - mapLast < MAP_MS) return false;
  mapLast = t0;
  st.posesDirty = false;
  if (st.poses.size === 0) { $('map-box').hidden = true; return true; }
  $('map-box').hidden = false;
  let x0 = Infinity, x1 = -Infinity, y0 = Infinity, y1 = -Infinity;
  for (const ps of st.poses.values()) for (const [x, y] of ps) { x0 = Math.min(x0, x); x1 = Math.max(x1, x); y0 = Math.min(y0, y); y1 = Math.max(y1, y); }
  // One scale on both axes, as large as the box allows.
  const pad = 24, xs = Math.max(x1 - x0, 1), ys = Math.max(y1 - y0, 1);
  const k = Math.min((widths.map - 2 * pad - 60) / xs, (300 - 2 * pad) / ys);
  const W = Math.max(xs * k + 2 * pad + 60, 280), H = ys * k + 2 * pad;
  const px = (x) => pad + (x - x0) * k, py = (y) => H - pad - (y - y0) * k;
  const span = Math.max(xs, ys);
  const parts = [`<rect width="${W}" height="${H}" fill="#eaf2fb"/>`];
  let i = 0;
  for (const [m, ps] of st.poses) {
    const color = TRACK[i++ % TRACK.length];
    const pts = ps.map(([x, y]) => px(x).toFixed(1) + ',' + py(y).toFixed(1)).join(' ');
    const [lx, ly] = ps[ps.length - 1];
    parts.push(`<polyline points="${pts}" fill="none" stroke="${color}" stroke-width="1.5"/>`);
    parts.push(`<circle cx="${px(lx)}" cy="${py(ly)}" r="4" fill="${color}"/><text x="${px(lx) + 6}" y="${py(ly) - 6}" font-size="11" fill="${color}">${esc(m)}</text>`);
  }
  parts.push(`<text x="${pad}" y="${H - 6}" font-size="10" fill="#6b7280">${span.toFixed(0)} m across (x east, y north)</text>`);
  $('map').innerHTML = `<svg width="${W}" height="${H}" xmlns="http://www.w3.org/2000/svg">${parts.join('')}</svg>`;
  return true;
}

// ---- header

function renderHeader(now) {
  $('time').textContent = now.toFixed(3);
  const o = outcomeOf(st);
  const out = $('outcome');
  if (o) { out.textContent = o; out.className = 'badge ' + o; } else if (st.outcomes.size > 0) {
    out.textContent = [...st.outcomes].map(([m, r]) => m + ': ' + r).join(', ');
    out.className = 'badge';
  } else { out.textContent = finished && info.mode === 'live' ? 'ended' : 'running'; out.className = 'badge'; }
  $('paused').hidden = !st.paused;
  const missions = $('mission-filter');
  for (const m of st.missions) {
    if (![...missions.options].some((o2) => o2.value === m)) missions.add(new Option(m, m));
  }
  const events = $('events');
  if (events.options.length !== st.events.size) events.innerHTML = [...st.events].map((e) => `<option value="${esc(e)}">`).join('');
}

// ---- rendering, once per animation frame

let pending = null;
let later = null;
let logFrom = 0;
let logReset = true;
// The last redraws' durations in milliseconds (benches-scripts/monitor-page-bench.py).
window.mclRenderMs = [];

// Records that arrive within one frame are drawn together. A hidden page
// is redrawn four times a second (browsers stop animation frames there).
function schedule() {
  if (pending !== null) return;
  pending = document.hidden ? setTimeout(render, 250) : requestAnimationFrame(render);
}

function render() {
  pending = null;
  const t0 = performance.now();
  const now = info.mode === 'replay' ? viewT : st.t;
  renderHeader(now);
  renderSources();
  renderTree();
  // The capped drawings come back later when they skipped this frame.
  const drawn = renderChrono(now, full) & renderMap();
  if (logReset) { renderLog(); logReset = false; } else appendLog(logFrom);
  logFrom = applied;
  st.dirty.clear();
  full = false;
  if (info.mode === 'replay') {
    const tmax = records.length ? records[records.length - 1].t : 0;
    $('slider').value = tmax > 0 ? Math.round((1000 * viewT) / tmax) : 1000;
  }
  $('conn').textContent = records.length + ' records' + (finished && info.mode === 'live' ? '; the run is over' : '');
  document.body.dataset.rendered = applied;
  if (!drawn && later === null) later = setTimeout(() => { later = null; schedule(); }, CHRONO_MS);
  const ms = window.mclRenderMs;
  ms.push(performance.now() - t0);
  if (ms.length > 10000) ms.splice(0, ms.length - 10000);
}

// ---- live

function follow() {
  const es = new EventSource('/api/events?from=0');
  es.addEventListener('records', (e) => {
    const msg = JSON.parse(e.data);
    if (msg.from !== records.length) return; // a reconnection sends again what we have
    for (const r of msg.records) { records.push(r); apply(st, r); }
    applied = records.length;
    if (typeof msg.pushed_ms === 'number') window.mclLatencyMs = Date.now() - msg.pushed_ms;
    schedule();
  });
  es.addEventListener('status', (e) => {
    if (JSON.parse(e.data).finished) {
      finished = true;
      es.close();
      $('operator').hidden = true;
      schedule();
    }
  });
  es.onerror = () => { if (!finished) $('conn').textContent = 'reconnecting…'; };
}

async function command(body) {
  const token = $('token').value;
  const vehicle = $('op-vehicle').value;
  if (vehicle) body.vehicle = vehicle;
  try {
    const res = await fetch('/api/operator', { method: 'POST', headers: { 'Content-Type': 'application/json', Authorization: 'Bearer ' + token }, body: JSON.stringify(body) });
    const j = await res.json().catch(() => ({}));
    $('op-result').textContent = res.ok ? body.command + ' sent' : `${body.command} refused (${res.status}): ${j.error || ''}`;
  } catch (e) {
    $('op-result').textContent = 'the monitor cannot be reached';
  }
}

// ---- replay

function seek(t) {
  if (t < viewT || applied === 0) { st = newState(); applied = 0; full = true; }
  while (applied < records.length && records[applied].t <= t + 1e-9) apply(st, records[applied++]);
  viewT = t;
  logReset = true;
  schedule();
}

function jump(pred, what) {
  // After the record of the last jump when the view is still at its time
  // (the records of that instant are all shown), else after what is shown.
  const from = jumpIndex >= 0 && records[jumpIndex].t === viewT ? jumpIndex + 1 : applied;
  for (let i = from; i < records.length; i++) {
    if (pred(records[i])) {
      jumpIndex = i;
      seek(records[i].t);
      $('jump').textContent = `${what} at t=${records[i].t.toFixed(3)}: ${records[i].kind} ${describe(records[i])}`;
      $('jump').dataset.index = i;
      return;
    }
  }
  $('jump').textContent = `no ${what} after t=${viewT.toFixed(3)}`;
}

function play() {
  if (playing) { clearInterval(playing); playing = null; $('play').textContent = 'Play'; return; }
  const tmax = records.length ? records[records.length - 1].t : 0;
  if (viewT >= tmax) seek(0);
  $('play').textContent = 'Pause';
  playing = setInterval(() => {
    const t = Math.min(tmax, viewT + 0.05 * Number($('speed').value));
    seek(t);
    if (t >= tmax) play();
  }, 50);
}

async function replay() {
  $('replay').hidden = false;
  const res = await fetch('/api/records');
  const msg = await res.json();
  for (const r of msg.records) records.push(r);
  finished = true;
  seek(0);
  $('slider').addEventListener('input', () => {
    const tmax = records.length ? records[records.length - 1].t : 0;
    jumpIndex = -1;
    seek((tmax * Number($('slider').value)) / 1000);
  });
  $('play').addEventListener('click', play);
  $('next-event').addEventListener('click', () => jump((r) => r.kind === 'event', 'event'));
  $('next-failure').addEventListener('click', () => jump(isFailure, 'failure'));
  $('next-coord').addEventListener('click', () => jump((r) => r.kind.startsWith('coord_'), 'coordination message'));
}

// ---- start

async function main() {
  info = await (await fetch('/api/info')).json();
  trees = await (await fetch('/api/tree')).json();
  $('title').textContent = info.title;
  $('mode').textContent = info.mode;
  document.title = 'MCL monitor — ' + info.title;
  document.querySelectorAll('#filters input, #filters select').forEach((el) => el.addEventListener('input', () => { logReset = true; schedule(); }));
  if (info.mode === 'replay') {
    await replay();
  } else {
    if (info.operator) {
      $('operator').hidden = false;
      const m = /token=([^&]+)/.exec(location.hash);
      if (m) $('token').value = decodeURIComponent(m[1]);
      // Several vehicles: the commands go to the one picked, or to every one (an answer needs one).
      if ((info.vehicles || []).length > 1) {
        $('op-vehicle').hidden = false;
        for (const v of info.vehicles) $('op-vehicle').append(new Option(v, v));
      }
      $('op-pause').addEventListener('click', () => command({ command: 'pause' }));
      $('op-resume').addEventListener('click', () => command({ command: 'resume' }));
      $('op-abort').addEventListener('click', () => command({ command: 'abort' }));
      $('op-answer').addEventListener('click', () => command({ command: 'answer', event: $('op-event').value }));
    }
    follow();
  }
  measure();
  window.addEventListener('resize', () => { measure(); full = true; logView.drawn = ''; schedule(); });
  $('chrono').addEventListener('scroll', () => { chronoView.top = $('chrono').scrollTop; chronoView.last = -Infinity; schedule(); });
  $('log-box').addEventListener('scroll', onLogScroll);
  document.body.dataset.ready = '1';
}

main();

// dibench report: the page's own code (no libraries). Reads the JSON block `dibench-data` and
// the base64 little-endian f32 pixel blocks it names, then builds the summary table, the
// convergence plot, the flip-book viewer, the error maps and the region statistics.
// Data layout: see src/report/mod.rs and docs/report.md.
(function () {
  'use strict';

  // An error while building the page is shown on it (and still reported to the console).
  window.addEventListener('error', (ev) => {
    const b = document.createElement('div');
    b.className = 'fatal';
    b.textContent = `report error: ${ev.message}`;
    document.body.prepend(b);
  });

  const $ = (id) => document.getElementById(id);
  const el = (tag, attrs, ...children) => {
    const e = document.createElement(tag);
    for (const [k, v] of Object.entries(attrs || {})) {
      if (v === undefined || v === null) continue;
      if (k === 'class') e.className = v;
      else if (k === 'text') e.textContent = v;
      else if (k.startsWith('on')) e.addEventListener(k.slice(2), v);
      else e.setAttribute(k, v);
    }
    for (const c of children) if (c !== null && c !== undefined) e.append(c);
    return e;
  };
  const SVG = 'http://www.w3.org/2000/svg';
  const svg = (tag, attrs, ...children) => {
    const e = document.createElementNS(SVG, tag);
    for (const [k, v] of Object.entries(attrs || {})) if (v !== undefined && v !== null) e.setAttribute(k, v);
    for (const c of children) if (c !== null && c !== undefined) e.append(c);
    return e;
  };

  // Numbers as the tables and the readout show them.
  function fmt(v, digits) {
    if (v === null || v === undefined) return '—';
    if (!Number.isFinite(v)) return String(v);
    if (v === 0) return '0';
    const a = Math.abs(v);
    if (a < 1e-3 || a >= 1e5) return v.toExponential(digits - 1);
    return v.toPrecision(digits);
  }
  // Table cells: 4 significant digits without trailing zeros.
  function fmtCell(v) {
    if (Number.isInteger(v) && Math.abs(v) < 1e9) return String(v);
    const t = fmt(v, 4);
    return t.includes('e') ? t.replace(/\.?0+e/, 'e') : t.includes('.') ? t.replace(/\.?0+$/, '') : t;
  }

  const DATA = JSON.parse($('dibench-data').textContent);
  const W = DATA.width;
  const H = DATA.height;
  const N = W * H;
  const EPS = DATA.eps;
  const LITTLE = new Uint8Array(new Uint16Array([1]).buffer)[0] === 1;

  // One pixel block: base64 of little-endian f32, `channels` per pixel.
  function decodeBlock(id, channels) {
    const node = $(id);
    if (!node) throw new Error(`pixel block ${id} is missing`);
    const bin = atob(node.textContent.trim());
    const want = N * channels * 4;
    if (bin.length !== want) throw new Error(`pixel block ${id}: ${bin.length} bytes, expected ${want}`);
    const bytes = new Uint8Array(want);
    for (let i = 0; i < want; i++) bytes[i] = bin.charCodeAt(i);
    node.textContent = ''; // the decoded copy is the one kept
    if (LITTLE) return new Float32Array(bytes.buffer);
    const dv = new DataView(bytes.buffer);
    const out = new Float32Array(want / 4);
    for (let i = 0; i < out.length; i++) out[i] = dv.getFloat32(4 * i, true);
    return out;
  }

  const PALETTE = ['#1f77b4', '#ff7f0e', '#2ca02c', '#d62728', '#9467bd', '#8c564b', '#e377c2',
    '#7f7f7f', '#bcbd22', '#17becf', '#393b79', '#ad494a', '#637939', '#8c6d31', '#7b4173'];
  const colourOf = (k) => (k < PALETTE.length ? PALETTE[k] : `hsl(${(k * 137.5) % 360} 60% 45%)`);

  // ---- the images ---------------------------------------------------------------------------
  const images = DATA.images.map((m, index) => ({
    ...m,
    index,
    rgb: decodeBlock(m.pixels, 3),
    varianceMap: m.variance ? decodeBlock(m.variance, 1) : null,
    flipMap: m.flip ? decodeBlock(m.flip, 1) : null,
  }));
  const refs = {};
  for (const im of images) if (im.kind === 'reference') refs[im.integrand] = im;
  const strategies = images.filter((im) => im.kind === 'strategy');
  strategies.forEach((s, k) => { s.colour = colourOf(k); s.number = k + 1; });
  for (const r of Object.values(refs)) r.colour = '#000';
  const byName = new Map(images.map((im) => [im.name, im]));

  // Per-pixel relMSE, mean over channels of (I − R)² / (R² + ε) (src/metrics.rs), in f64.
  for (const s of strategies) {
    const r = refs[s.integrand].rgb;
    const m = new Float32Array(N);
    for (let p = 0; p < N; p++) {
      let acc = 0;
      for (let c = 0; c < 3; c++) {
        const i = 3 * p + c;
        const d = s.rgb[i] - r[i];
        acc += (d * d) / (r[i] * r[i] + EPS);
      }
      m[p] = acc / 3;
    }
    s.relmseMap = m;
  }

  // A log10 scale over maps: the 1st to 99.9th percentile of their positive values (as
  // `dibench plot` scales the variance), from at most about a million samples.
  function logRange(maps) {
    const vals = [];
    const total = maps.reduce((n, m) => n + m.length, 0);
    const step = Math.max(1, Math.floor(total / 1e6));
    for (const m of maps) for (let i = 0; i < m.length; i += step) {
      const v = m[i];
      if (v > 0 && Number.isFinite(v)) vals.push(Math.log10(v));
    }
    if (!vals.length) return { lo: -3, hi: 0 };
    vals.sort((a, b) => a - b);
    const q = (f) => vals[Math.floor((vals.length - 1) * f)];
    let lo = q(0.01);
    let hi = q(0.999);
    if (!(hi > lo)) { lo -= 0.5; hi += 0.5; }
    return { lo, hi };
  }
  const MAPS = {
    relmse: {
      title: 'relMSE', key: 'relmseMap', log: true, cmap: 'viridis',
      range: logRange(strategies.map((s) => s.relmseMap)),
      what: `per-pixel relMSE, mean over RGB of (I − R)² / (R² + ε), ε = ${EPS}`,
    },
    variance: {
      title: 'variance', key: 'varianceMap', log: true, cmap: 'viridis',
      range: logRange(strategies.filter((s) => s.varianceMap).map((s) => s.varianceMap)),
      what: 'per-pixel variance of the mean, mean over RGB (<stem>.variance.exr)',
    },
    flip: {
      title: 'FLIP', key: 'flipMap', log: false, cmap: 'magma', range: { lo: 0, hi: 1 },
      what: 'FLIP error (<stem>.flip.exr), 0 to 1',
    },
  };
  const LUT = {};
  for (const [name, arr] of Object.entries(DATA.colormaps)) LUT[name] = Uint8Array.from(arr);

  // ---- state ---------------------------------------------------------------------------------
  const state = {
    cur: strategies.length ? strategies[0].index : 0,
    lastStrategy: strategies.length ? strategies[0].index : null,
    mode: 'image',
    exposure: 0,
    scale: 1, tx: 0, ty: 0, fitted: true,
    region: null, // {x0, y0, x1, y1}, half-open pixel bounds
    drag: null,
    hover: null,
    hidden: new Set(), // plot lines switched off
  };

  // ---- rendering an image or a map into an image-sized canvas ---------------------------------
  const cache = new Map();
  function srgb8(v) {
    if (Number.isNaN(v)) return -1;
    if (!(v > 0)) return 0;
    const s = v <= 0.0031308 ? 12.92 * v : 1.055 * Math.pow(v, 1 / 2.4) - 0.055;
    return s >= 1 ? 255 : Math.round(s * 255);
  }
  function imageData(im, mode) {
    const out = new ImageData(W, H);
    const d = out.data;
    const map = mode === 'image' ? null : MAPS[mode];
    const values = map && im[map.key];
    if (!values) {
      const gain = Math.pow(2, state.exposure);
      const src = im.rgb;
      for (let p = 0; p < N; p++) {
        const r = srgb8(src[3 * p] * gain);
        const g = srgb8(src[3 * p + 1] * gain);
        const b = srgb8(src[3 * p + 2] * gain);
        if (r < 0 || g < 0 || b < 0 || !Number.isFinite(src[3 * p] + src[3 * p + 1] + src[3 * p + 2])) {
          d[4 * p] = 255; d[4 * p + 1] = 0; d[4 * p + 2] = 255; // NaN or ∞: magenta
        } else {
          d[4 * p] = r; d[4 * p + 1] = g; d[4 * p + 2] = b;
        }
        d[4 * p + 3] = 255;
      }
      return out;
    }
    const lut = LUT[map.cmap];
    const { lo, hi } = map.range;
    for (let p = 0; p < N; p++) {
      const v = values[p];
      let k;
      if (Number.isNaN(v)) k = -1;
      else {
        const t = map.log ? (v > 0 ? (Math.log10(v) - lo) / (hi - lo) : 0) : (v - lo) / (hi - lo);
        k = Math.round(Math.min(1, Math.max(0, t)) * 255);
      }
      if (k < 0) { d[4 * p] = 255; d[4 * p + 1] = 0; d[4 * p + 2] = 255; } else {
        d[4 * p] = lut[3 * k]; d[4 * p + 1] = lut[3 * k + 1]; d[4 * p + 2] = lut[3 * k + 2];
      }
      d[4 * p + 3] = 255;
    }
    return out;
  }
  // What image `im` shows in `mode`: the map, or the tone-mapped image where it has none.
  const shows = (im, mode) => (mode !== 'image' && im[MAPS[mode].key] ? mode : 'image');
  function bitmap(im, mode) {
    const m = shows(im, mode);
    const key = `${im.index}|${m}|${m === 'image' ? state.exposure : ''}`;
    let c = cache.get(key);
    if (!c) {
      c = document.createElement('canvas');
      c.width = W; c.height = H;
      c.getContext('2d').putImageData(imageData(im, m), 0, 0);
      cache.set(key, c);
    }
    return c;
  }
  function dropImageBitmaps() {
    for (const k of [...cache.keys()]) if (k.split('|')[1] === 'image') cache.delete(k);
  }

  // ---- header ---------------------------------------------------------------------------------
  function header() {
    const run = DATA.run || {};
    $('title').textContent = `${DATA.scene || 'run'} · ${DATA.run_id}`;
    const seeds = Array.isArray(run.seeds) ? run.seeds.join(', ') : '';
    const refs = Array.isArray(run.reference_spp) ? run.reference_spp.map((p) => `${p[0]} ${p[1]} spp`).join(', ') : '';
    const items = [
      ['status', run.status], ['budget', run.budget_s !== undefined ? `${run.budget_s} s per strategy` : undefined],
      ['runs', run.runs !== undefined ? `${run.runs} (seeds ${seeds})` : undefined], ['image', `${W}×${H}`],
      ['backend', run.backend ? `${run.backend}${run.isa ? ' / ' + run.isa : ''}` : undefined],
      ['threads', run.threads], ['cpu', run.cpu_model], ['samplers', Array.isArray(run.samplers) ? run.samplers.join(', ') : undefined],
      ['reference', refs], ['dibench', run.dibench_version ? `${run.dibench_version} (${run.commit})` : undefined],
    ];
    const meta = $('run-meta');
    for (const [k, v] of items) {
      if (v === undefined || v === null || v === '') continue;
      meta.append(el('span', { class: k === 'status' && v !== 'complete' ? 'meta bad' : 'meta' }, el('b', { text: k }), ` ${v}`));
    }
    const notes = $('notes');
    for (const n of DATA.notes || []) notes.append(el('li', { text: n }));
    if (run.sampler_note) notes.append(el('li', { text: run.sampler_note }));
    for (const s of run.skipped || []) notes.append(el('li', { text: `skipped ${s.name}: ${s.reason}` }));
    $('generator').textContent = `written by ${DATA.generator}; data format ${DATA.format}`;
  }

  // ---- summary table --------------------------------------------------------------------------
  function summaryTable() {
    const { columns, rows } = DATA.summary;
    const first = ['strategy', 'sampler', 'integrand'].filter((c) => columns.includes(c));
    const order = [...first, ...columns.filter((c) => !first.includes(c) && c !== 'scene')];
    const idx = order.map((c) => columns.indexOf(c));
    const numeric = idx.map((i) => rows.every((r) => r[i].trim() === '' || Number.isFinite(Number(r[i]))) &&
      rows.some((r) => r[i].trim() !== ''));
    // The columns shown by default; the others with "all columns".
    const KEY = ['strategy', 'sampler', 'integrand', 'runs', 'spp_mean', 'rmse_mean', 'rmse_ci95', 'rmse_debiased',
      'relmse_debiased_mean', 'relmse_debiased_ci95', 'efficiency', 'predicted_rmse', 'slope_time_mean', 'holm_p_vs_best', 'vs_best'];
    const extra = order.map((c) => !KEY.includes(c) && !c.includes('flip'));
    const table = $('summary-table');
    table.classList.add('compact');
    $('all-columns').addEventListener('change', (ev) => table.classList.toggle('compact', !ev.target.checked));
    const thead = el('thead');
    const tbody = el('tbody');
    const tr = el('tr');
    order.forEach((c, k) => tr.append(el('th', {
      'data-col': c, class: `${numeric[k] ? 'num' : ''}${extra[k] ? ' extra' : ''}`, title: numeric[k] ? 'numeric: click to sort' : 'click to sort',
      onclick: () => sortBy(k),
    }, c)));
    thead.append(tr);
    const body = rows.map((r) => {
      const strategy = r[columns.indexOf('strategy')];
      const sampler = columns.includes('sampler') ? r[columns.indexOf('sampler')] : 'independent';
      const im = strategies.find((s) => s.strategy === strategy && s.sampler === sampler);
      const row = el('tr', { 'data-name': im ? im.name : strategy, onclick: () => im && select(im.index, true) });
      order.forEach((c, k) => {
        const raw = r[idx[k]];
        const td = el('td', { 'data-col': c, 'data-value': raw });
        if (numeric[k]) {
          td.className = 'num';
          td.textContent = raw.trim() === '' ? '—' : fmtCell(Number(raw));
          td.title = raw;
        } else if (c === 'vs_best') {
          const v = raw.trim();
          td.className = `verdict ${v === 'best' ? 'v-best' : v === 'worse' ? 'v-worse' : v === 'tie' ? 'v-tie' : 'v-none'}`;
          td.append(el('span', { text: v || '—' }));
        } else if (c === 'strategy' && im) {
          td.append(el('i', { class: 'swatch', style: `background:${im.colour}` }), raw);
        } else td.textContent = raw;
        if (extra[k]) td.classList.add('extra');
        row.append(td);
      });
      return { row, raw: r };
    });
    for (const b of body) tbody.append(b.row);
    table.append(thead, tbody);
    let sorted = { k: -1, dir: 1 };
    function sortBy(k) {
      sorted = { k, dir: sorted.k === k ? -sorted.dir : 1 };
      const i = idx[k];
      const key = (r) => (numeric[k] ? (r[i].trim() === '' ? null : Number(r[i])) : r[i]);
      const list = body.slice().sort((a, b) => {
        const x = key(a.raw);
        const y = key(b.raw);
        if (x === null || y === null) return x === y ? 0 : x === null ? 1 : -1; // empty last
        const c = numeric[k] ? x - y : String(x).localeCompare(String(y), undefined, { numeric: true });
        return c * sorted.dir;
      });
      for (const b of list) tbody.append(b.row);
      thead.querySelectorAll('th').forEach((th, j) => {
        th.classList.toggle('sorted-asc', j === k && sorted.dir > 0);
        th.classList.toggle('sorted-desc', j === k && sorted.dir < 0);
        if (j === k) th.setAttribute('aria-sort', sorted.dir > 0 ? 'ascending' : 'descending');
        else th.removeAttribute('aria-sort');
      });
    }
  }

  // ---- convergence plot (inline SVG) ------------------------------------------------------------
  function series(metric, xcol) {
    const { columns, rows } = DATA.results;
    const col = (n) => columns.indexOf(n);
    const [cs, csa, ci, cr, ck, cx, cy] = ['strategy', 'sampler', 'integrand', 'run', 'checkpoint', xcol, metric].map(col);
    const out = new Map();
    for (const r of rows) {
      const sampler = csa >= 0 ? r[csa] : 'independent';
      const im = strategies.find((s) => s.strategy === r[cs] && s.sampler === sampler);
      const name = im ? im.name : (sampler === 'independent' ? r[cs] : `${r[cs]}.${sampler}`);
      if (!out.has(name)) out.set(name, { name, integrand: r[ci], colour: im ? im.colour : '#888', runs: new Map() });
      const s = out.get(name);
      const x = Number(r[cx]);
      const y = Number(r[cy]);
      if (!(x > 0 && y > 0 && Number.isFinite(x) && Number.isFinite(y))) continue;
      const run = r[cr];
      if (!s.runs.has(run)) s.runs.set(run, []);
      s.runs.get(run).push({ k: Number(r[ck]), x, y });
    }
    for (const s of out.values()) {
      const at = new Map();
      for (const pts of s.runs.values()) {
        pts.sort((a, b) => a.k - b.k);
        for (const p of pts) {
          if (!at.has(p.k)) at.set(p.k, []);
          at.get(p.k).push(p);
        }
      }
      s.mean = [...at.entries()].sort((a, b) => a[0] - b[0]).map(([k, ps]) => ({
        k, n: ps.length,
        x: ps.reduce((a, p) => a + p.x, 0) / ps.length,
        y: ps.reduce((a, p) => a + p.y, 0) / ps.length,
      }));
    }
    return [...out.values()].filter((s) => s.mean.length);
  }
  function logTicks(lo, hi) {
    const a = Math.floor(Math.log10(lo));
    const b = Math.ceil(Math.log10(hi));
    const mult = b - a <= 2 ? [1, 2, 5] : [1];
    const t = [];
    for (let e = a; e <= b; e++) for (const m of mult) {
      const v = m * Math.pow(10, e);
      if (v >= lo * 0.999 && v <= hi * 1.001) t.push({ v, major: m === 1, e, m });
    }
    return t;
  }
  function tickLabel(t) {
    const text = svg('text', {});
    if (t.e >= -2 && t.e <= 3) { text.textContent = String(+t.v.toPrecision(3)); return text; }
    text.append(t.m === 1 ? '10' : `${t.m}·10`);
    text.append(svg('tspan', { dy: '-0.5em', 'font-size': '0.75em' }, String(t.e)));
    return text;
  }
  function plot() {
    const metric = $('plot-metric').value;
    const xcol = $('plot-x').value;
    const host = $('plot');
    host.textContent = '';
    const ss = series(metric, xcol);
    if (!ss.length) { host.append(el('p', { text: 'results.csv has no positive values to plot' })); return; }
    const Wp = 900, Hp = 460, m = { l: 70, r: 230, t: 16, b: 46 };
    const pw = Wp - m.l - m.r, ph = Hp - m.t - m.b;
    let x0 = Infinity, x1 = 0, y0 = Infinity, y1 = 0;
    for (const s of ss) for (const pts of s.runs.values()) for (const p of pts) {
      x0 = Math.min(x0, p.x); x1 = Math.max(x1, p.x); y0 = Math.min(y0, p.y); y1 = Math.max(y1, p.y);
    }
    x0 /= 1.25; x1 *= 1.25; y0 /= 1.5; y1 *= 1.5;
    const X = (v) => m.l + (Math.log(v / x0) / Math.log(x1 / x0)) * pw;
    const Y = (v) => m.t + ph - (Math.log(v / y0) / Math.log(y1 / y0)) * ph;
    const root = svg('svg', { viewBox: `0 0 ${Wp} ${Hp}`, width: Wp, height: Hp, class: 'plot', role: 'img',
      'aria-label': `${metric} against ${xcol}, log-log` });
    const clip = svg('clipPath', { id: 'plot-clip' }, svg('rect', { x: m.l, y: m.t, width: pw, height: ph }));
    root.append(svg('defs', {}, clip));
    const grid = svg('g', { class: 'grid' });
    for (const t of logTicks(x0, x1)) {
      grid.append(svg('line', { x1: X(t.v), x2: X(t.v), y1: m.t, y2: m.t + ph, class: t.major ? 'major' : 'minor' }));
      const l = tickLabel(t);
      l.setAttribute('x', X(t.v)); l.setAttribute('y', m.t + ph + 18); l.setAttribute('text-anchor', 'middle');
      grid.append(l);
    }
    for (const t of logTicks(y0, y1)) {
      grid.append(svg('line', { x1: m.l, x2: m.l + pw, y1: Y(t.v), y2: Y(t.v), class: t.major ? 'major' : 'minor' }));
      const l = tickLabel(t);
      l.setAttribute('x', m.l - 8); l.setAttribute('y', Y(t.v) + 4); l.setAttribute('text-anchor', 'end');
      grid.append(l);
    }
    root.append(grid);
    root.append(svg('rect', { x: m.l, y: m.t, width: pw, height: ph, class: 'frame' }));
    root.append(svg('text', { x: m.l + pw / 2, y: Hp - 8, 'text-anchor': 'middle', class: 'axis-title' }, xcol === 'spp' ? 'samples per pixel' : 'time [s]'));
    root.append(svg('text', { transform: `translate(16 ${m.t + ph / 2}) rotate(-90)`, 'text-anchor': 'middle', class: 'axis-title' },
      metric === 'rmse' ? 'RMSE' : 'relMSE'));
    const lines = svg('g', { 'clip-path': 'url(#plot-clip)' });
    // The guide: RMSE ∝ x^−½ (relMSE ∝ x^−1) through the lowest first point.
    const slope = metric === 'rmse' ? -0.5 : -1;
    const lowest = ss.map((s) => s.mean[0]).reduce((a, b) => (b.y < a.y ? b : a));
    lines.append(svg('line', { x1: X(lowest.x), y1: Y(lowest.y * 0.7), x2: X(x1), y2: Y(lowest.y * 0.7 * Math.pow(x1 / lowest.x, slope)),
      class: 'guide' }));
    for (const s of ss) {
      const g = svg('g', { class: 'series', 'data-name': s.name, style: `color:${s.colour}` });
      if (state.hidden.has(s.name)) g.style.display = 'none';
      for (const pts of s.runs.values()) {
        if (s.runs.size > 1) g.append(svg('polyline', { class: 'run', points: pts.map((p) => `${X(p.x)},${Y(p.y)}`).join(' ') }));
      }
      g.append(svg('polyline', { class: 'mean', points: s.mean.map((p) => `${X(p.x)},${Y(p.y)}`).join(' ') }));
      for (const p of s.mean) {
        g.append(svg('circle', { cx: X(p.x), cy: Y(p.y), r: 3 },
          svg('title', {}, `${s.name}: ${xcol} ${fmt(p.x, 4)}, ${metric} ${fmt(p.y, 4)} (checkpoint ${p.k}, mean of ${p.n} run${p.n > 1 ? 's' : ''})`)));
      }
      lines.append(g);
    }
    root.append(lines);
    const legend = svg('g', { class: 'legend' });
    const multi = new Set(ss.map((s) => s.integrand)).size > 1;
    // Top to bottom as the lines end.
    const byEnd = ss.slice().sort((a, b) => b.mean[b.mean.length - 1].y - a.mean[a.mean.length - 1].y);
    byEnd.forEach((s, k) => {
      const y = m.t + 8 + k * 18;
      const item = svg('g', { class: state.hidden.has(s.name) ? 'item off' : 'item', transform: `translate(${m.l + pw + 14} ${y})`, style: `color:${s.colour}`, 'data-name': s.name });
      item.append(svg('line', { x1: 0, x2: 22, y1: 0, y2: 0 }), svg('text', { x: 28, y: 4 }, multi ? `${s.name} (${s.integrand})` : s.name));
      item.addEventListener('click', () => {
        if (state.hidden.has(s.name)) state.hidden.delete(s.name); else state.hidden.add(s.name);
        plot();
      });
      legend.append(item);
    });
    const gy = m.t + 8 + ss.length * 18;
    legend.append(svg('g', { class: 'item guide-item', transform: `translate(${m.l + pw + 14} ${gy})` },
      svg('line', { x1: 0, x2: 22, y1: 0, y2: 0, class: 'guide' }), svg('text', { x: 28, y: 4 }, `slope ${slope === -1 ? '−1' : '−½'}`)));
    root.append(legend);
    host.append(root);
  }

  // ---- viewer ---------------------------------------------------------------------------------
  const canvas = $('view');
  const ctx = canvas.getContext('2d');
  let cssW = 0, cssH = 0, dpr = 1;
  const thumbs = []; // {canvas, ctx, im, mode}

  function resize() {
    const wrap = canvas.parentElement;
    dpr = window.devicePixelRatio || 1;
    cssW = Math.max(200, wrap.clientWidth);
    cssH = Math.round(Math.min(Math.max(320, cssW * H / W), window.innerHeight * 0.78));
    canvas.style.width = `${cssW}px`;
    canvas.style.height = `${cssH}px`;
    canvas.width = Math.round(cssW * dpr);
    canvas.height = Math.round(cssH * dpr);
    if (state.fitted) fit();
    layoutThumbs();
    redraw();
  }
  function fitScale() {
    const s = Math.min(cssW / W, cssH / H) * 0.98;
    return s >= 1 ? Math.floor(s) : s;
  }
  function fit() {
    state.scale = fitScale();
    state.tx = (cssW - W * state.scale) / 2;
    state.ty = (cssH - H * state.scale) / 2;
    state.fitted = true;
  }
  function oneToOne() {
    const cx = cssW / 2, cy = cssH / 2;
    zoomAt(cx, cy, 1 / dpr / state.scale);
  }
  function zoomAt(cx, cy, factor) {
    const s = Math.min(512, Math.max(Math.min(0.05, fitScale() / 4), state.scale * factor));
    state.tx = cx - (cx - state.tx) * (s / state.scale);
    state.ty = cy - (cy - state.ty) * (s / state.scale);
    state.scale = s;
    state.fitted = false;
    redraw();
  }

  let pending = false;
  function redraw() {
    if (pending) return;
    pending = true;
    requestAnimationFrame(() => { pending = false; drawNow(); });
  }
  // Draws `im` in `mode` on canvas `c` with image pixel (x, y) at device pixel
  // (T.tx + x·T.s, T.ty + y·T.s); the region on top, and on the main view the pixel grid and
  // the hovered pixel.
  function drawView(c, g, im, mode, T, main) {
    g.setTransform(1, 0, 0, 1, 0, 0);
    g.fillStyle = '#1c1c1e';
    g.fillRect(0, 0, c.width, c.height);
    g.setTransform(T.s, 0, 0, T.s, T.tx, T.ty);
    g.imageSmoothingEnabled = false;
    g.drawImage(bitmap(im, mode), 0, 0);
    g.setTransform(1, 0, 0, 1, 0, 0);
    const X = (x) => T.tx + x * T.s;
    const Y = (y) => T.ty + y * T.s;
    if (main && T.s >= 24) {
      // The pixel grid, once pixels are large.
      const px0 = Math.max(0, Math.floor(-T.tx / T.s)), px1 = Math.min(W, Math.ceil((c.width - T.tx) / T.s));
      const py0 = Math.max(0, Math.floor(-T.ty / T.s)), py1 = Math.min(H, Math.ceil((c.height - T.ty) / T.s));
      g.strokeStyle = 'rgba(128,128,128,0.35)';
      g.lineWidth = 1;
      g.beginPath();
      for (let x = px0; x <= px1; x++) { const v = Math.round(X(x)) + 0.5; g.moveTo(v, Y(py0)); g.lineTo(v, Y(py1)); }
      for (let y = py0; y <= py1; y++) { const v = Math.round(Y(y)) + 0.5; g.moveTo(X(px0), v); g.lineTo(X(px1), v); }
      g.stroke();
    }
    const rect = state.drag && state.drag.kind === 'region' ? state.drag.rect : state.region;
    if (rect) {
      const x = X(rect.x0), y = Y(rect.y0), w = (rect.x1 - rect.x0) * T.s, h = (rect.y1 - rect.y0) * T.s;
      const u = main ? dpr : 1;
      g.lineWidth = 1.5 * u;
      g.strokeStyle = 'rgba(0,0,0,0.8)';
      g.setLineDash([]);
      g.strokeRect(x, y, w, h);
      g.strokeStyle = '#ffd400';
      g.setLineDash([5 * u, 4 * u]);
      g.strokeRect(x, y, w, h);
      g.setLineDash([]);
    }
    if (main && state.hover) {
      g.strokeStyle = 'rgba(255,255,255,0.9)';
      g.lineWidth = 1;
      g.strokeRect(X(state.hover.x) + 0.5, Y(state.hover.y) + 0.5, T.s - 1, T.s - 1);
    }
  }
  // The part of the image the main view shows (the whole image when none of it is in view).
  function visibleRect() {
    const x0 = Math.max(0, -state.tx / state.scale), x1 = Math.min(W, (cssW - state.tx) / state.scale);
    const y0 = Math.max(0, -state.ty / state.scale), y1 = Math.min(H, (cssH - state.ty) / state.scale);
    return x1 > x0 && y1 > y0 ? { x0, y0, x1, y1 } : { x0: 0, y0: 0, x1: W, y1: H };
  }
  function drawNow() {
    const im = images[state.cur];
    drawView(canvas, ctx, im, state.mode, { s: state.scale * dpr, tx: state.tx * dpr, ty: state.ty * dpr }, true);
    // The error maps show what the main view shows, fitted to their size.
    const v = visibleRect();
    for (const t of thumbs) {
      const k = Math.min(t.canvas.width / (v.x1 - v.x0), t.canvas.height / (v.y1 - v.y0));
      const T = { s: k, tx: (t.canvas.width - (v.x1 - v.x0) * k) / 2 - v.x0 * k, ty: (t.canvas.height - (v.y1 - v.y0) * k) / 2 - v.y0 * k };
      drawView(t.canvas, t.ctx, t.im, t.mode, T, false);
    }
  }
  // The label, the message and the legend of the view (at once, not at the next frame).
  function updateChrome() {
    const im = images[state.cur];
    const shown = shows(im, state.mode);
    const label = im.kind === 'reference'
      ? `${im.name} (${im.integrand}${im.spp ? `, ${im.spp} spp` : ''})`
      : `${im.number} · ${im.name}`;
    $('view-label').textContent = `${label} · ${shown === 'image' ? `exposure ${state.exposure >= 0 ? '+' : ''}${state.exposure.toFixed(1)}` : MAPS[shown].title}`;
    $('view-label').style.borderColor = im.colour || '#000';
    $('view-message').textContent = shown !== state.mode
      ? (im.kind === 'reference' ? `the reference has no ${MAPS[state.mode].title} map: showing the image`
        : state.mode === 'flip' ? `no FLIP map (${im.name}.flip.exr absent): showing the image`
          : `no variance map for ${im.name} (a non-independent sampler writes none): showing the image`)
      : '';
    legend($('legend'), shown);
  }

  function imageList() {
    const list = $('image-list');
    for (const im of images) {
      const key = im.kind === 'reference' ? (Object.keys(refs).length === 1 ? '0' : '') : (im.number <= 9 ? String(im.number) : '');
      const li = el('li', { 'data-name': im.name, class: im.kind, onclick: () => select(im.index, false) },
        el('kbd', { text: key || ' ' }),
        el('i', { class: 'swatch', style: `background:${im.colour}` }),
        el('span', { class: 'name', text: im.name }),
        im.kind === 'strategy' && Object.keys(refs).length > 1 ? el('small', { text: ` ${im.integrand}` }) : null);
      list.append(li);
    }
  }
  function select(index, scroll) {
    if (index < 0 || index >= images.length) return;
    state.cur = index;
    if (images[index].kind === 'strategy') state.lastStrategy = index;
    $('image-list').querySelectorAll('li').forEach((li, k) => li.classList.toggle('current', k === index));
    document.querySelectorAll('#summary-table tbody tr').forEach((tr) => tr.classList.toggle('current', tr.dataset.name === images[index].name));
    if (scroll) $('viewer').scrollIntoView({ behavior: 'instant', block: 'start' });
    updateReadout();
    updateChrome();
    redraw();
  }
  function referenceOf(im) {
    return im.kind === 'reference' ? im : refs[im.integrand];
  }
  function toggleReference() {
    const im = images[state.cur];
    if (im.kind === 'strategy') select(referenceOf(im).index);
    else if (state.lastStrategy !== null) select(state.lastStrategy);
  }
  function setMode(mode) {
    if (!MAPS[mode] && mode !== 'image') return;
    state.mode = mode;
    document.querySelectorAll('#modes input').forEach((i) => { i.checked = i.value === mode; });
    updateReadout();
    updateChrome();
    redraw();
  }
  function setExposure(e) {
    state.exposure = Math.round(Math.min(12, Math.max(-12, e)) * 10) / 10;
    $('exposure').value = state.exposure;
    $('exposure-value').textContent = `${state.exposure >= 0 ? '+' : ''}${state.exposure.toFixed(1)}`;
    dropImageBitmaps();
    updateChrome();
    redraw();
  }

  // A colour bar with numbers for the map `mode` (nothing for the image).
  function legend(host, mode) {
    if (host.dataset.mode === mode) return;
    host.dataset.mode = mode;
    host.textContent = '';
    if (mode === 'image') return;
    host.append(colourBar(MAPS[mode]));
  }
  function colourBar(map) {
    const wrap = el('div', { class: 'colourbar' });
    const bar = el('canvas', { width: 256, height: 1 });
    const g = bar.getContext('2d');
    const d = new ImageData(256, 1);
    const lut = LUT[map.cmap];
    for (let i = 0; i < 256; i++) { d.data[4 * i] = lut[3 * i]; d.data[4 * i + 1] = lut[3 * i + 1]; d.data[4 * i + 2] = lut[3 * i + 2]; d.data[4 * i + 3] = 255; }
    g.putImageData(d, 0, 0);
    const ticks = el('div', { class: 'ticks' });
    const { lo, hi } = map.range;
    for (let k = 0; k <= 4; k++) {
      const t = k / 4;
      const v = map.log ? Math.pow(10, lo + t * (hi - lo)) : lo + t * (hi - lo);
      ticks.append(el('span', { style: `left:${100 * t}%`, text: map.log ? v.toExponential(1) : v.toFixed(2) }));
    }
    wrap.append(el('div', { class: 'bar-title', text: `${map.title}: ${map.what}${map.log ? ' · log scale, 1st–99.9th percentile over all strategies; values outside take the ends' : ''}` }), bar, ticks);
    return wrap;
  }

  // ---- readout --------------------------------------------------------------------------------
  function pixel(im, x, y) {
    const p = 3 * (y * W + x);
    return [im.rgb[p], im.rgb[p + 1], im.rgb[p + 2]];
  }
  function updateReadout() {
    const out = $('readout');
    if (!state.hover) return;
    const { x, y } = state.hover;
    const im = images[state.cur];
    const [r, g, b] = pixel(im, x, y);
    const ref = referenceOf(im);
    const parts = [`x ${x} y ${y}`, `${im.name}: R ${fmt(r, 7)} G ${fmt(g, 7)} B ${fmt(b, 7)}`];
    if (im !== ref) {
      const [rr, rg, rb] = pixel(ref, x, y);
      parts.push(`reference: R ${fmt(rr, 7)} G ${fmt(rg, 7)} B ${fmt(rb, 7)}`);
      parts.push(`relMSE ${fmt(im.relmseMap[y * W + x], 4)}`);
      if (im.varianceMap) parts.push(`variance ${fmt(im.varianceMap[y * W + x], 4)}`);
      if (im.flipMap) parts.push(`FLIP ${fmt(im.flipMap[y * W + x], 4)}`);
    }
    out.textContent = '';
    parts.forEach((t, k) => out.append(el('span', { class: k === 1 ? 'px main' : 'px', text: t })));
    Object.assign(out.dataset, { x, y, r, g, b, name: im.name });
  }
  function toImage(ev) {
    const rect = canvas.getBoundingClientRect();
    const cx = ev.clientX - rect.left, cy = ev.clientY - rect.top;
    return { cx, cy, fx: (cx - state.tx) / state.scale, fy: (cy - state.ty) / state.scale };
  }
  const clampX = (v) => Math.min(W - 1, Math.max(0, v));
  const clampY = (v) => Math.min(H - 1, Math.max(0, v));

  function regionFrom(a, b) {
    const x0 = clampX(Math.floor(Math.min(a.fx, b.fx))), x1 = clampX(Math.floor(Math.max(a.fx, b.fx))) + 1;
    const y0 = clampY(Math.floor(Math.min(a.fy, b.fy))), y1 = clampY(Math.floor(Math.max(a.fy, b.fy))) + 1;
    return { x0, y0, x1, y1 };
  }

  function viewerEvents() {
    canvas.addEventListener('wheel', (ev) => {
      ev.preventDefault();
      const { cx, cy } = toImage(ev);
      const dy = ev.deltaMode === 1 ? ev.deltaY * 16 : ev.deltaMode === 2 ? ev.deltaY * 400 : ev.deltaY;
      zoomAt(cx, cy, Math.exp(-dy * 0.0015));
    }, { passive: false });
    canvas.addEventListener('pointerdown', (ev) => {
      if (ev.button !== 0) return;
      canvas.focus({ preventScroll: true });
      canvas.setPointerCapture(ev.pointerId);
      const p = toImage(ev);
      state.drag = ev.shiftKey
        ? { kind: 'region', start: p, rect: regionFrom(p, p) }
        : { kind: 'pan', cx: p.cx, cy: p.cy, tx: state.tx, ty: state.ty };
      canvas.classList.toggle('panning', !ev.shiftKey);
      ev.preventDefault();
    });
    canvas.addEventListener('pointermove', (ev) => {
      const p = toImage(ev);
      const d = state.drag;
      if (d && d.kind === 'pan') {
        state.tx = d.tx + p.cx - d.cx;
        state.ty = d.ty + p.cy - d.cy;
        state.fitted = false;
      } else if (d && d.kind === 'region') {
        d.rect = regionFrom(d.start, p);
      }
      const x = Math.floor(p.fx), y = Math.floor(p.fy);
      const inside = x >= 0 && y >= 0 && x < W && y < H;
      const changed = !state.hover !== !inside || (inside && (state.hover.x !== x || state.hover.y !== y));
      state.hover = inside ? { x, y } : null;
      if (changed) updateReadout();
      redraw();
    });
    const end = (ev) => {
      const d = state.drag;
      if (!d) return;
      state.drag = null;
      canvas.classList.remove('panning');
      if (d.kind === 'region') {
        d.rect = regionFrom(d.start, toImage(ev));
        setRegion(d.rect);
      }
      redraw();
    };
    canvas.addEventListener('pointerup', end);
    canvas.addEventListener('pointercancel', end);
    canvas.addEventListener('pointerleave', () => { if (!state.drag) { state.hover = null; redraw(); } });
    canvas.addEventListener('dblclick', () => { fit(); redraw(); });
    $('exposure').addEventListener('input', (ev) => setExposure(Number(ev.target.value)));
    document.querySelectorAll('#modes input').forEach((i) => i.addEventListener('change', () => setMode(i.value)));
    $('fit').addEventListener('click', () => { fit(); redraw(); });
    $('one').addEventListener('click', oneToOne);
    $('clear-region').addEventListener('click', () => setRegion(null));
    $('plot-metric').addEventListener('change', plot);
    $('plot-x').addEventListener('change', plot);
    window.addEventListener('resize', resize);
    document.addEventListener('keydown', (ev) => {
      if (ev.ctrlKey || ev.metaKey || ev.altKey) return;
      const t = ev.target;
      if (t && (t.tagName === 'SELECT' || (t.tagName === 'INPUT' && t.type !== 'range' && t.type !== 'radio'))) return;
      const k = ev.key;
      let handled = true;
      if (k >= '1' && k <= '9') { const s = strategies[Number(k) - 1]; if (s) select(s.index); }
      else if (k === '0' || k === 'r') select(referenceOf(images[state.cur]).index);
      else if (k === 'ArrowRight' || k === 'ArrowDown') select((state.cur + 1) % images.length);
      else if (k === 'ArrowLeft' || k === 'ArrowUp') select((state.cur + images.length - 1) % images.length);
      else if (k === ' ') toggleReference();
      else if (k === 'i') setMode('image');
      else if (k === 'e') setMode('relmse');
      else if (k === 'v') setMode('variance');
      else if (k === 'p') setMode('flip');
      else if (k === '+' || k === '=') setExposure(state.exposure + 0.5);
      else if (k === '-' || k === '_') setExposure(state.exposure - 0.5);
      else if (k === 'x') setExposure(0);
      else if (k === 'f') { fit(); redraw(); }
      else if (k === 'o') oneToOne();
      else if (k === 'Escape') setRegion(null);
      else handled = false;
      if (handled) { ev.preventDefault(); if (t && t.blur && t.type === 'range') t.blur(); }
    });
  }

  // ---- region statistics ------------------------------------------------------------------------
  function stats(s, x0, y0, x1, y1) {
    const r = refs[s.integrand].rgb;
    let se = 0, rel = 0, v = 0;
    for (let y = y0; y < y1; y++) {
      for (let x = x0; x < x1; x++) {
        const p = y * W + x;
        for (let c = 0; c < 3; c++) {
          const i = 3 * p + c;
          const d = s.rgb[i] - r[i];
          se += d * d;
          rel += (d * d) / (r[i] * r[i] + EPS);
        }
        if (s.varianceMap) v += s.varianceMap[p];
      }
    }
    const n = (x1 - x0) * (y1 - y0);
    return { rmse: Math.sqrt(se / (3 * n)), relmse: rel / (3 * n), variance: s.varianceMap ? v / n : null, pixels: n };
  }
  function regionStats(x0, y0, x1, y1) {
    x0 = Math.max(0, Math.floor(x0)); y0 = Math.max(0, Math.floor(y0));
    x1 = Math.min(W, Math.floor(x1)); y1 = Math.min(H, Math.floor(y1));
    if (!(x1 > x0 && y1 > y0)) return null;
    const out = {};
    for (const s of strategies) out[s.name] = stats(s, x0, y0, x1, y1);
    return out;
  }
  const whole = {};
  function setRegion(rect) {
    state.region = rect && rect.x1 > rect.x0 && rect.y1 > rect.y0 ? rect : null;
    regionTable();
    redraw();
  }
  function regionTable() {
    const table = $('region-table');
    table.textContent = '';
    const r = state.region;
    const st = r ? regionStats(r.x0, r.y0, r.x1, r.y1) : null;
    const cap = r ? `region x ${r.x0}–${r.x1 - 1}, y ${r.y0}–${r.y1 - 1} (${r.x1 - r.x0}×${r.y1 - r.y0} pixels)` : 'no region selected (shift + drag on the image): whole image only';
    table.append(el('caption', { id: 'region-caption', text: cap }));
    table.append(el('thead', {}, el('tr', {},
      ...['strategy', 'integrand', 'RMSE (region)', 'relMSE (region)', 'variance (region)', 'RMSE (image)', 'relMSE (image)']
        .map((h) => el('th', { text: h })))));
    const body = el('tbody');
    const best = {};
    if (st) for (const s of strategies) {
      const v = st[s.name].relmse;
      if (!(s.integrand in best) || v < best[s.integrand]) best[s.integrand] = v;
    }
    for (const s of strategies) {
      const a = st ? st[s.name] : null;
      const w = whole[s.name];
      const tr = el('tr', { 'data-name': s.name, 'data-rmse': a ? a.rmse : '', 'data-relmse': a ? a.relmse : '', onclick: () => select(s.index) },
        el('td', {}, el('i', { class: 'swatch', style: `background:${s.colour}` }), s.name),
        el('td', { text: s.integrand }),
        el('td', { class: 'num', text: a ? fmt(a.rmse, 4) : '—' }),
        el('td', { class: a && a.relmse === best[s.integrand] ? 'num best' : 'num', text: a ? fmt(a.relmse, 4) : '—' }),
        el('td', { class: 'num', text: a && a.variance !== null ? fmt(a.variance, 4) : '—' }),
        el('td', { class: 'num', text: fmt(w.rmse, 4) }),
        el('td', { class: 'num', text: fmt(w.relmse, 4) }));
      body.append(tr);
    }
    table.append(body);
  }

  // ---- error map grid -----------------------------------------------------------------------------
  function errorMaps() {
    const legends = $('errormap-legends');
    for (const m of ['relmse', 'variance', 'flip']) legends.append(colourBar(MAPS[m]));
    const grid = $('errormap-grid');
    grid.append(el('div', { class: 'gh' }), ...['relMSE', 'variance of the mean', 'FLIP'].map((t) => el('div', { class: 'gh', text: t })));
    for (const s of strategies) {
      grid.append(el('div', { class: 'glabel' }, el('i', { class: 'swatch', style: `background:${s.colour}` }), `${s.number} · ${s.name}`,
        Object.keys(refs).length > 1 ? el('small', { text: ` ${s.integrand}` }) : null));
      for (const mode of ['relmse', 'variance', 'flip']) {
        if (!s[MAPS[mode].key]) {
          const why = mode === 'flip' ? 'no FLIP map' : 'no variance map (non-independent sampler)';
          grid.append(el('div', { class: 'gcell missing', 'data-name': s.name, 'data-mode': mode, text: why }));
          continue;
        }
        const c = el('canvas', { class: 'thumb', 'data-name': s.name, 'data-mode': mode, title: `${s.name}: ${MAPS[mode].title} (click to view)` });
        c.addEventListener('click', () => { select(s.index, true); setMode(mode); });
        grid.append(el('div', { class: 'gcell' }, c));
        thumbs.push({ canvas: c, ctx: c.getContext('2d'), im: s, mode });
      }
    }
  }
  function layoutThumbs() {
    const tw = 260;
    const th = Math.round(tw * Math.min(1.5, H / W));
    for (const t of thumbs) {
      t.canvas.style.width = `${tw}px`;
      t.canvas.style.height = `${th}px`;
      t.canvas.width = Math.round(tw * dpr);
      t.canvas.height = Math.round(th * dpr);
    }
  }

  // ---- start --------------------------------------------------------------------------------------
  header();
  summaryTable();
  plot();
  imageList();
  errorMaps();
  for (const s of strategies) whole[s.name] = stats(s, 0, 0, W, H);
  regionTable();
  viewerEvents();
  resize();
  select(state.cur);
  setExposure(0);

  // The hook the browser test (tests/browser) drives the page through; also handy from the
  // console. Pixel coordinates are from the top-left; regions are half-open [x0,x1)×[y0,y1).
  window.dibenchReport = {
    format: DATA.format,
    width: W,
    height: H,
    images: images.map((im) => im.name),
    strategies: strategies.map((s) => s.name),
    current: () => images[state.cur].name,
    mode: () => state.mode,
    exposure: () => state.exposure,
    select: (name) => { const im = byName.get(name); if (im) select(im.index); return !!im; },
    setMode,
    pixel: (name, x, y) => { const im = byName.get(name); return im ? pixel(im, x, y) : null; },
    mapValue: (name, mode, x, y) => { const im = byName.get(name); const m = im && MAPS[mode] && im[MAPS[mode].key]; return m ? m[y * W + x] : null; },
    info: (name) => {
      const im = byName.get(name);
      if (!im) return null;
      let finite = 0, sum = 0;
      for (const v of im.rgb) if (Number.isFinite(v)) { finite++; sum += v; }
      return { kind: im.kind, integrand: im.integrand, values: im.rgb.length, finite, sum, variance: !!im.varianceMap, flip: !!im.flipMap };
    },
    regionStats,
    region: () => (state.region ? { ...state.region } : null),
    wholeStats: () => JSON.parse(JSON.stringify(whole)),
    view: () => ({ scale: state.scale, tx: state.tx, ty: state.ty }),
    // The client (CSS pixel) coordinates of the centre of image pixel (x, y) in the viewer.
    screenOf: (x, y) => {
      const r = canvas.getBoundingClientRect();
      return { x: r.left + state.tx + (x + 0.5) * state.scale, y: r.top + state.ty + (y + 0.5) * state.scale };
    },
    ready: true,
  };
  document.body.classList.add('ready');
})();

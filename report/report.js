/* Lash report page: reads the JSON in <script id="lash-data"> (docs/report-data.md) and draws
 * the summary, the animation with its clearance insets, the uPlot charts and the analysis tables.
 * Vanilla JS, no network: uPlot is inlined before this script. Every section copes with a
 * missing or null key by writing "not computed". window.lashReport exposes the charts to the
 * page test (tests/report/check_report.mjs). */
(function () {
  'use strict';

  // --- constants shared with report.css ---------------------------------------------------------
  const PALETTE = ['#4e79a7', '#e15759', '#59a14f', '#f28e2b', '#b07aa1', '#76b7b2', '#edc948',
                   '#9c755f', '#ff9da7', '#3b8bc2'];
  const MODE_COLOR = {free: '#4e79a7', impact: '#f28e2b', continuous: '#e15759', contact: '#e15759'};
  const MODE_LABEL = {free: 'free flight', impact: 'impact', continuous: 'continuous contact',
                      contact: 'contact'};
  const AXIS_STROKE = '#3a4252';
  const GRID = {stroke: 'rgba(0,0,0,0.07)', width: 1};
  const TICKS = {stroke: 'rgba(0,0,0,0.25)', width: 1, size: 4};
  const AXIS_FONT = '11px system-ui, "DejaVu Sans", sans-serif';
  const LABEL_FONT = '600 11.5px system-ui, "DejaVu Sans", sans-serif';
  const BODY_QUANTITIES = new Set(['x', 'y', 'phi', 'vx', 'vy', 'omega', 'ax', 'ay', 'alpha']);
  const PREFIXABLE = new Set(['m', 'N', 'N·m', 'J', 'W', 's', 'Hz']);
  const SI_PREFIX = {'-9': 'n', '-6': 'µ', '-3': 'm', '0': '', '3': 'k', '6': 'M', '9': 'G'};
  const SUPERSCRIPT = {'-': '⁻', '0': '⁰', '1': '¹', '2': '²', '3': '³', '4': '⁴', '5': '⁵',
                       '6': '⁶', '7': '⁷', '8': '⁸', '9': '⁹'};

  // --- state exposed to the page test -----------------------------------------------------------
  const report = window.lashReport = {ready: false, charts: [], insets: [], animation: null};

  // --- small DOM and number helpers -------------------------------------------------------------
  function el(tag, attrs, ...children) {
    const node = document.createElement(tag);
    for (const [k, v] of Object.entries(attrs || {})) {
      if (v == null || v === false) continue;
      if (k === 'class') node.className = v;
      else if (k === 'text') node.textContent = v;
      else if (k.startsWith('on')) node.addEventListener(k.slice(2), v);
      else node.setAttribute(k, v === true ? '' : v);
    }
    for (const c of children.flat()) {
      if (c == null || c === false) continue;
      node.append(c instanceof Node ? c : document.createTextNode(String(c)));
    }
    return node;
  }
  const isNum = (v) => typeof v === 'number' && Number.isFinite(v);
  const present = (v) => v !== null && v !== undefined;
  const isEmptyObj = (v) => !present(v) || (typeof v === 'object' && Object.keys(v).length === 0);

  /** Compact number for tables and legends: 4 significant digits, e-notation outside 1e-3..1e5. */
  function fmt(v, digits) {
    if (!present(v)) return '–';
    if (typeof v !== 'number') return String(v);
    if (!Number.isFinite(v)) return String(v);
    if (v === 0) return '0';
    const p = digits || 4;
    const a = Math.abs(v);
    const s = (a >= 1e5 || a < 1e-3) ? v.toExponential(p - 1).replace(/\.?0+e/, 'e').replace('e+', 'e')
                                     : String(parseFloat(v.toPrecision(p)));
    return s.replace('-', '−');
  }
  /** Tick label: the shortest exact representation of an already nicely rounded value. */
  function fmtTick(v) {
    if (!present(v)) return '';
    const a = Math.abs(v);
    if (a !== 0 && (a >= 1e6 || a < 1e-4)) return fmt(v, 3);
    return String(parseFloat(v.toPrecision(10))).replace('-', '−');
  }
  /** The colour mixed towards black by the fraction k (ideal twins: same hue, darker, dashed). */
  function shade(hex, k) {
    const n = parseInt(hex.slice(1, 7), 16);
    const ch = [n >> 16, (n >> 8) & 255, n & 255].map((c) => Math.round(c * (1 - k)));
    return '#' + ch.map((c) => c.toString(16).padStart(2, '0')).join('');
  }
  const sup = (n) => String(n).split('').map((c) => SUPERSCRIPT[c] || c).join('');

  /** Display scale for values of one unit: an SI prefix (mm, kN) or a power of ten (10³ m/s²). */
  function displayScale(unit, maxAbs) {
    if (!isNum(maxAbs) || maxAbs === 0) return {f: 1, unit: unit};
    let e = 3 * Math.floor(Math.log10(maxAbs) / 3);
    e = Math.max(-9, Math.min(9, e));
    if (e === 0) return {f: 1, unit: unit};
    if (PREFIXABLE.has(unit) && !(unit === 'm' && e > 0) && !(unit === 's' && e > 0))
      return {f: Math.pow(10, -e), unit: SI_PREFIX[e] + unit};
    return {f: Math.pow(10, -e), unit: '10' + sup(e) + (unit ? ' ' + unit : '')};
  }
  function maxAbsOf(arrays) {
    let m = 0;
    for (const a of arrays) for (const v of a || []) if (isNum(v) && Math.abs(v) > m) m = Math.abs(v);
    return m;
  }
  const splitChannel = (name) => {
    const k = name.lastIndexOf('.');
    return k < 0 ? ['', name] : [name.slice(0, k), name.slice(k + 1)];
  };
  /** The channel_info entry of a channel (own keys only: a channel may be called 'constructor'). */
  const infoOf = (channel) => (Object.prototype.hasOwnProperty.call(channelInfo, channel) ? channelInfo[channel] : null);
  /** SI unit of a channel as the data gives it (channel_info, written by the engine); '' when the
   *  data does not say. Never guessed from the name. */
  function unitOf(channel) {
    const info = infoOf(channel);
    return info && typeof info.unit === 'string' ? info.unit : '';
  }
  /** Short description of a channel from channel_info; the channel's name when the data has none. */
  function descriptionOf(channel) {
    const info = infoOf(channel);
    return info && typeof info.description === 'string' && info.description ? info.description : channel;
  }
  const unitText = (u) => (u ? u : '–');

  function notComputed(parent, what) {
    parent.append(el('p', {class: 'not-computed', text: (what ? what + ': ' : '') + 'not computed'}));
  }

  // --- data ------------------------------------------------------------------------------------------
  let D;
  try {
    D = JSON.parse(document.getElementById('lash-data').textContent);
  } catch (err) {
    document.getElementById('main').append(el('p', {class: 'error',
      text: 'This report carries no valid data (the JSON in <script id="lash-data"> did not parse: ' +
            err.message + ').'}));
    throw err;
  }
  const model = D.model || {};
  const series = D.series || {};
  const channels = series.channels || {};
  const ideal = series.ideal || {};
  const analysis = D.analysis || {};
  // Unit and description of every channel (docs/report-data.md); an older file has none.
  const hasChannelInfo = D.channel_info !== null && typeof D.channel_info === 'object' && !Array.isArray(D.channel_info);
  const channelInfo = hasChannelInfo ? D.channel_info : {};
  const joints = Array.isArray(model.joints) ? model.joints : [];
  const bodies = Array.isArray(model.bodies) ? model.bodies : [];
  const drivers = Array.isArray(model.drivers) ? model.drivers : [];
  const clearanceJoints = joints.filter((j) => j && j.clearance);
  const modelName = model.name || 'model';

  // Body colours: one per body, in model order, used in the animation and nowhere else.
  const bodyColor = {};
  bodies.forEach((b, i) => { bodyColor[b.name] = PALETTE[i % PALETTE.length]; });

  // --- uPlot helpers ----------------------------------------------------------------------------
  function autoSize(self, values, axisIdx, cycleNum) {
    const axis = self.axes[axisIdx];
    if (cycleNum > 1) return axis._size;
    let size = axis.ticks.size + axis.gap;
    const longest = (values || []).reduce((acc, v) => (v && v.length > acc.length ? v : acc), '');
    if (longest !== '') {
      self.ctx.font = axis.font[0];
      size += self.ctx.measureText(longest).width / devicePixelRatio;
    }
    return Math.ceil(size) + (axis.label ? 4 : 0);
  }
  function axis(opts) {
    const scale = opts.scale;
    const f = opts.f || 1;
    return Object.assign({
      stroke: AXIS_STROKE, grid: GRID, ticks: TICKS, font: AXIS_FONT, labelFont: LABEL_FONT,
      labelSize: 18, gap: 4,
      values: (u, splits) => splits.map((v) => fmtTick(v * f)),
    }, opts.side === 0 || opts.side === 2 ? {size: 28} : {size: autoSize}, opts,
    {scale: scale});
  }
  function chartWidth(container) {
    return Math.max(280, Math.floor(container.getBoundingClientRect().width || 600));
  }
  /** Creates a chart, registers it for resizing and for the page test. */
  function makeChart(container, id, opts, data, fixedAspect) {
    container.replaceChildren();
    const width = chartWidth(container);
    opts.width = fixedAspect ? Math.min(width, opts.height || width) : width;
    const u = new uPlot(opts, data, container);
    const entry = {id: id, u: u, container: container};
    // Square plot area (orbits, Poincaré sections): widen or narrow by what the axes take.
    entry.fit = () => {
      const avail = chartWidth(container);
      if (!fixedAspect) { u.setSize({width: avail, height: u.height}); return; }
      const dpr = window.devicePixelRatio || 1;
      const extra = u.width - u.bbox.width / dpr, plotH = u.bbox.height / dpr;
      const w = Math.min(avail, Math.round(plotH + extra));
      if (Math.abs(w - u.width) > 1) u.setSize({width: w, height: u.height});
    };
    if (fixedAspect) entry.fit();
    report.charts = report.charts.filter((c) => c.id !== id);
    report.charts.push(entry);
    return u;
  }
  /** mode-2 paths: a polyline in data order (orbits, phase portraits). */
  function xyLinePaths(u, si) {
    const d = u.data[si];
    const xs = d[0], ys = d[1];
    const p = new Path2D();
    let pen = false;
    for (let i = 0; i < xs.length; i++) {
      if (!isNum(xs[i]) || !isNum(ys[i])) { pen = false; continue; }
      const x = u.valToPos(xs[i], 'x', true), y = u.valToPos(ys[i], 'y', true);
      if (pen) p.lineTo(x, y); else { p.moveTo(x, y); pen = true; }
    }
    return {stroke: p, fill: null, clip: null, flags: 0};
  }
  /** mode-2 paths: small filled dots (Poincaré points). */
  function xyDotPaths(u, si) {
    const d = u.data[si];
    const s = u.series[si];
    const r = 3.2 * devicePixelRatio;
    const p = new Path2D();
    for (let i = 0; i < d[0].length; i++) {
      if (!isNum(d[0][i]) || !isNum(d[1][i])) continue;
      const x = u.valToPos(d[0][i], 'x', true), y = u.valToPos(d[1][i], 'y', true);
      p.moveTo(x + r, y);
      p.arc(x, y, r, 0, 2 * Math.PI);
    }
    u.ctx.save();
    u.ctx.fillStyle = s._stroke || s.stroke;
    u.ctx.fill(p);
    u.ctx.restore();
    return null;
  }
  function downloadPng(u, name) {
    const src = u.ctx.canvas;
    const c = document.createElement('canvas');
    c.width = src.width; c.height = src.height;
    const g = c.getContext('2d');
    g.fillStyle = '#fff'; g.fillRect(0, 0, c.width, c.height);
    g.drawImage(src, 0, 0);
    const a = el('a', {href: c.toDataURL('image/png'), download: name + '.png'});
    document.body.append(a); a.click(); a.remove();
  }
  function chartBlock(title, id, note) {
    const holder = el('div', {class: 'chart', id: 'chart-' + id});
    const btn = el('button', {class: 'small', title: 'Save this plot as PNG', text: 'PNG',
      onclick: () => {
        const c = report.charts.find((x) => x.id === id);
        if (c) downloadPng(c.u, modelName + '_' + id);
      }});
    // Without a title the caller places the button (time-series groups put it in their heading).
    const head = title ? el('div', {class: 'chart-title'}, el('span', {text: title}), btn) : null;
    return {node: el('div', {}, head, note ? el('div', {class: 'legend-note', text: note}) : null, holder),
            holder: holder, button: btn};
  }

  // --- tables -----------------------------------------------------------------------------------------
  function table(headers, rows, numericCols) {
    const num = new Set(numericCols || []);
    const t = el('table', {class: 'data'},
      el('thead', {}, el('tr', {}, headers.map((h, i) => el('th', {class: num.has(i) ? 'num' : null, text: h})))),
      el('tbody', {}, rows.map((r) => el('tr', {}, r.map((c, i) =>
        c instanceof Node ? el('td', {}, c) : el('td', {class: num.has(i) ? 'num' : null, text: c}))))));
    return el('div', {class: 'table-scroll'}, t);
  }
  /** "Copy" button: the table as tab-separated text, ready for a spreadsheet or a paper draft. */
  function copyButton(getTable) {
    return el('button', {class: 'small', title: 'Copy the table as tab-separated text', text: 'Copy TSV',
      onclick: (ev) => {
        const t = getTable();
        const tsv = Array.from(t.querySelectorAll('tr')).map((tr) =>
          Array.from(tr.children).map((c) => c.textContent.replace(/−/g, '-')).join('\t')).join('\n');
        const done = () => { ev.target.textContent = 'Copied'; setTimeout(() => { ev.target.textContent = 'Copy TSV'; }, 1200); };
        if (navigator.clipboard && navigator.clipboard.writeText) navigator.clipboard.writeText(tsv).then(done, () => {});
      }});
  }
  /** A sub-heading with its own "Copy TSV" button, then the table. */
  function titledTable(title, headers, rows, numericCols) {
    const t = table(headers, rows, numericCols);
    return [el('div', {class: 'group-head'}, el('h3', {text: title}), copyButton(() => t.querySelector('table'))), t];
  }
  function section(id, title, tocLabel, tools) {
    const s = el('section', {class: 'card', id: id},
      el('div', {class: 'card-head'}, el('h2', {text: title}), tools ? el('div', {class: 'tools'}, tools) : null));
    document.getElementById('main').append(s);
    document.getElementById('toc-links').append(el('a', {href: '#' + id, text: tocLabel || title}));
    return s;
  }

  // --- header: name, status, verdict, integrator statistics --------------------------------------
  function renderHeader() {
    document.title = 'Lash report — ' + modelName;
    document.getElementById('title').textContent = modelName;
    const badges = document.getElementById('badges');
    const st = D.status;
    if (st && st.ok === true) badges.append(el('span', {class: 'badge ok',
      text: 'run completed' + (isNum(st.time) && st.time > 0 ? ' · t = ' + fmt(st.time * 1e3) + ' ms' : '')}));
    else if (st && st.ok === false) badges.append(el('span', {class: 'badge bad',
      text: 'run stopped' + (isNum(st.time) ? ' at t = ' + fmt(st.time * 1e3) + ' ms' : '')}));
    else badges.append(el('span', {class: 'badge info', text: 'status unknown'}));
    const v = analysis.verdict;
    if (v && v.class) {
      const cls = {periodic: 'ok', 'quasi-periodic': 'warn', chaotic: 'bad'}[v.class] || 'info';
      badges.append(el('a', {href: '#verdict', class: 'badge ' + cls, text: 'verdict: ' + v.class}));
    }
    const sol = model.solver || {};
    const bits = [];
    if (model.file) bits.push(model.file);
    bits.push(bodies.length + ' bodies', joints.length + ' joints', clearanceJoints.length + ' with clearance');
    if (sol.integrator) bits.push(sol.integrator + (isNum(sol.end_time) ? ' to ' + fmt(sol.end_time * 1e3) + ' ms' : ''));
    document.getElementById('subtitle').textContent = bits.join(' · ');

    const s = section('summary', 'Run summary', 'Summary');
    if (st && st.ok === false) {
      s.append(el('div', {class: 'banner bad'},
        'The integration stopped at t = ' + fmt(st.time) + ' s' + (st.element ? ' in ' + st.element : '') +
        (st.message ? ': ' + st.message : '') + '. The results below end there.'));
    }
    const I = D.integrator;
    const figs = el('div', {class: 'figures'});
    const fig = (k, v, title) => figs.append(el('div', {class: 'figure', title: title || null},
      el('div', {class: 'v', text: v}), el('div', {class: 'k', text: k})));
    if (I) {
      fig('integrator', I.name || '–');
      fig('steps', fmtInt(I.steps), 'accepted integration steps');
      fig('rejected steps' + (isNum(I.steps) && isNum(I.rejected_steps) && I.steps + I.rejected_steps > 0
        ? ' (' + (100 * I.rejected_steps / (I.steps + I.rejected_steps)).toFixed(1) + ' % of tries)' : ''), fmtInt(I.rejected_steps));
      fig('RHS evaluations', fmtInt(I.rhs_evaluations), 'right-hand-side (equations of motion) evaluations');
      fig('events', fmtInt(I.events), 'located events: contact onsets, separations, sections');
      fig('outputs', fmtInt(I.outputs), 'rows written to timeseries.csv');
      fig('wall time', isNum(I.wall_seconds) ? fmtSeconds(I.wall_seconds) : '–');
    }
    fig('max constraint violation', fmt(D.max_constraint_violation, 3));
    s.append(figs);
    if (!I) notComputed(s, 'integrator statistics');
  }
  function fmtInt(v) { return isNum(v) ? Math.round(v).toLocaleString('en-US') : '–'; }
  function fmtSeconds(s) { return s < 1 ? fmt(s * 1e3, 3) + ' ms' : fmt(s, 3) + ' s'; }

  // --- model summary -----------------------------------------------------------------------------
  function renderModel() {
    const s = section('model', 'Model', 'Model');
    if (isEmptyObj(D.model)) { notComputed(s); return; }
    const pt = (p) => (Array.isArray(p) ? '(' + p.map((v) => fmt(v)).join(',\u00a0') + ')' : '–');
    const grid = el('div', {class: 'grid2'});
    const holder = el('div');
    holder.append(...titledTable('Bodies', ['body', 'mass [kg]', 'inertia [kg·m²]', 'markers (body frame) [m]'],
      bodies.map((b) => [b.name, fmt(b.mass), fmt(b.inertia),
        Object.entries(b.markers || {}).map(([k, p]) => k + ' ' + pt(p)).join(',  ')]), [1, 2]));
    const gm = model.ground_markers || {};
    if (Object.keys(gm).length)
      holder.append(el('p', {class: 'legend-note', text: 'Ground markers [m]: ' +
        Object.entries(gm).map(([k, p]) => k + ' ' + pt(p)).join(',  ')}));
    grid.append(holder);
    const right = el('div');
    if (drivers.length) {
      right.append(...titledTable('Drivers', ['driver', 'joint', 'speed [rad/s]', 'speed [rpm]', 'profile'],
        drivers.map((d) => [d.name, d.joint, fmt(d.speed), isNum(d.speed) ? fmt(d.speed * 30 / Math.PI) : '–',
                            d.profile || '–']), [2, 3]));
    } else { right.append(el('h3', {text: 'Drivers'})); notComputed(right, 'drivers'); }
    const sol = model.solver || {};
    right.append(...titledTable('Solver', ['setting', 'value'], Object.entries(sol).map(([k, v]) =>
      [k.replace(/_/g, ' ') + ({end_time: ' [s]', output_interval: ' [s]', max_step: ' [s]'}[k] || ''),
       typeof v === 'number' ? fmt(v) : String(v)]), [1]));
    grid.append(right);
    s.append(grid);

    const end = (e) => (e ? e.body + ' ' + pt(e.point) : '–');
    const mm = (v) => (isNum(v) ? fmt(v * 1e3) : '–');
    s.append(...titledTable('Joints', ['joint', 'type', 'journal / guide', 'bearing / slider', 'axis',
                    'clearance [mm]', 'R journal [mm]', 'R bearing [mm]', 'normal law', 'friction'],
      joints.map((j) => {
        const c = j.clearance;
        return [j.name, j.type, end(j.a), end(j.b), j.axis ? pt(j.axis) : '–',
                c ? mm(c.clearance) : 'ideal', c ? mm(c.journal_radius) : '–', c ? mm(c.bearing_radius) : '–',
                c ? c.normal_law || '–' : '–', c ? c.friction_law || '–' : '–'];
      }), [5, 6, 7]));
  }

  // --- animation -----------------------------------------------------------------------------------
  function episodeLookup(name) {
    const cj = analysis.clearance && analysis.clearance[name];
    const eps = cj && cj.modes && Array.isArray(cj.modes.episodes) ? cj.modes.episodes : null;
    if (!eps) return null;
    const starts = eps.map((e) => e[0]);
    return (t) => {
      let lo = 0, hi = starts.length - 1, k = -1;
      while (lo <= hi) { const m = (lo + hi) >> 1; if (starts[m] <= t) { k = m; lo = m + 1; } else hi = m - 1; }
      if (k >= 0 && t <= eps[k][1]) return eps[k][2] === 'impact' ? 'impact' : 'continuous';
      return 'free';
    };
  }

  function renderAnimation() {
    const s = section('animation', 'Mechanism', 'Animation');
    const F = D.frames;
    if (!F || !Array.isArray(F.time) || F.time.length === 0 || isEmptyObj(F.bodies)) {
      notComputed(s, 'animation frames'); return;
    }
    const nFrames = F.time.length;
    const markers = {};
    bodies.forEach((b) => {
      markers[b.name] = Object.values(b.markers || {}).filter((p) => Array.isArray(p));
    });
    const groundMarkers = Object.values(model.ground_markers || {});
    // A one-marker body (a slider) is drawn as a block around the largest bearing it carries.
    const blockRadius = {};
    clearanceJoints.forEach((j) => {
      const r = j.clearance.bearing_radius || 0;
      [j.a, j.b].forEach((e) => { if (e) blockRadius[e.body] = Math.max(blockRadius[e.body] || 0, r); });
    });
    const pose = (name, k) => (F.bodies[name] ? F.bodies[name][k] : null);
    // Flexible links: drawn as a parabola through their ends, bent by their mid-length deflection
    // from the chord, magnified so that the largest one shows as a tenth of the link's length.
    const flexDefl = F.deflection || {};
    const flexible = {};
    let flexMag = 0;
    {
      let ratio = 0;
      bodies.forEach((b) => {
        const w = flexDefl[b.name];
        if (!b.flexible || !Array.isArray(w) || w.length !== nFrames || !(b.flexible.length > 0)) return;
        flexible[b.name] = {length: b.flexible.length, w: w};
        w.forEach((v) => { if (isFinite(v)) ratio = Math.max(ratio, Math.abs(v) / b.flexible.length); });
      });
      if (ratio > 0) flexMag = Math.max(1, 0.1 / ratio);
    }
    const world = (q, p) => {
      const c = Math.cos(q[2]), sn = Math.sin(q[2]);
      return [q[0] + c * p[0] - sn * p[1], q[1] + sn * p[0] + c * p[1]];
    };
    const jointPoint = (e, k) => {
      if (!e || !Array.isArray(e.point)) return null;
      if (e.body === 'ground') return e.point;
      const q = pose(e.body, k);
      return q ? world(q, e.point) : null;
    };

    // Scene bounds over all frames.
    let x0 = Infinity, x1 = -Infinity, y0 = Infinity, y1 = -Infinity;
    const grow = (p, r) => {
      if (!p) return; r = r || 0;
      x0 = Math.min(x0, p[0] - r); x1 = Math.max(x1, p[0] + r);
      y0 = Math.min(y0, p[1] - r); y1 = Math.max(y1, p[1] + r);
    };
    groundMarkers.forEach((p) => grow(p));
    for (let k = 0; k < nFrames; k++) {
      for (const b of bodies) {
        const q = pose(b.name, k);
        if (!q) continue;
        grow(q);
        markers[b.name].forEach((p) => grow(world(q, p)));
      }
    }
    joints.forEach((j) => { if (j.clearance) grow(jointPoint(j.b, 0), j.clearance.bearing_radius || 0); });
    if (!isFinite(x0)) { notComputed(s, 'animation frames'); return; }
    const span = Math.max(x1 - x0, y1 - y0, 1e-6);
    const margin = 0.08 * span;
    x0 -= margin; x1 += margin; y0 -= margin; y1 += margin;

    const layout = el('div', {class: 'anim-layout'});
    const mainCol = el('div', {class: 'anim-main'});
    const canvas = el('canvas', {id: 'anim-canvas'});
    const play = el('button', {id: 'anim-play', text: '▶ Play'});
    const slider = el('input', {id: 'anim-slider', type: 'range', min: 0, max: nFrames - 1, step: 1, value: 0});
    const speed = el('select', {id: 'anim-speed', title: 'playback speed'},
      [['0.25', '¼×'], ['0.5', '½×'], ['1', '1×'], ['2', '2×'], ['4', '4×']].map(([v, t]) =>
        el('option', {value: v, selected: v === '1' ? true : null, text: t})));
    const readout = el('span', {id: 'anim-readout'});
    mainCol.append(canvas, el('div', {class: 'anim-controls'}, play, slider, speed, readout));
    const tEnd = F.time[nFrames - 1];
    mainCol.append(el('div', {class: 'legend-note',
      text: nFrames + ' frames over ' + fmt(tEnd * 1e3) + ' ms; 1× plays 60 frames per second. ' +
            'Bodies through their markers; circles at clearance joints are the bearing and journal at true size.' +
            (flexMag > 0 ? ' Flexible links bent by their mid-length deflection, magnified ×' + fmt(flexMag) +
             ' (a parabola through their ends).' : '')}));
    layout.append(mainCol);

    // Clearance insets.
    const insetCol = el('div', {class: 'insets'});
    const insets = [];
    clearanceJoints.forEach((j, idx) => {
      const ecc = F.clearance && F.clearance[j.name];
      if (!Array.isArray(ecc) || ecc.length !== nFrames) return;
      const c = el('canvas', {class: 'inset-canvas', 'data-joint': j.name});
      const title = el('div', {class: 'inset-title', text: (idx + 1) + '  ' + j.name});
      insetCol.append(el('div', {class: 'inset'}, title, c));
      // The trail comes from the denser series when they hold the eccentricity, else from the frames.
      const sx = channels[j.name + '.ex'], sy = channels[j.name + '.ey'];
      const dense = Array.isArray(series.time) && sx && sy && sx.length === series.time.length && sy.length === sx.length;
      insets.push({joint: j, canvas: c, ecc: ecc, mode: episodeLookup(j.name), tag: idx + 1, title: title,
                   trail: dense ? {t: series.time, x: sx, y: sy} : null});
    });
    if (insets.length) {
      insetCol.append(el('div', {class: 'mode-key'},
        ['free', 'impact', 'continuous'].map((m) => el('span', {}, el('i', {style: 'background:' + MODE_COLOR[m]}), MODE_LABEL[m]))));
      layout.append(insetCol);
    } else if (clearanceJoints.length) {
      insetCol.append(el('p', {class: 'not-computed', text: 'clearance insets: not computed'}));
      layout.append(insetCol);
    }
    s.append(layout);

    const crank = Array.isArray(series.crank_angle) && Array.isArray(series.time) ? series : null;
    const crankAt = (t) => {
      if (!crank) return null;
      const ts = crank.time;
      let lo = 0, hi = ts.length - 1;
      while (lo < hi) { const m = (lo + hi + 1) >> 1; if (ts[m] <= t) lo = m; else hi = m - 1; }
      return crank.crank_angle[lo];
    };

    let W = 0, H = 0, scale = 1, ox = 0, oy = 0, dpr = 1;
    function resize() {
      dpr = window.devicePixelRatio || 1;
      W = Math.max(300, canvas.getBoundingClientRect().width || 640);
      const aspect = (y1 - y0) / (x1 - x0);
      H = Math.round(Math.max(200, Math.min(400, W * aspect)));
      canvas.style.height = H + 'px';
      canvas.width = Math.round(W * dpr); canvas.height = Math.round(H * dpr);
      scale = Math.min(W / (x1 - x0), H / (y1 - y0));
      ox = (W - scale * (x1 - x0)) / 2; oy = (H - scale * (y1 - y0)) / 2;
      insets.forEach((ins) => {
        const r = ins.canvas.getBoundingClientRect();
        const w = r.width || 210, h = r.height || 210;
        ins.canvas.width = Math.round(w * dpr); ins.canvas.height = Math.round(h * dpr);
        ins.w = w; ins.h = h;
      });
    }
    const X = (p) => ox + (p[0] - x0) * scale;
    const Y = (p) => H - oy - (p[1] - y0) * scale;

    function convexHull(pts) {
      const p = pts.slice().sort((a, b) => a[0] - b[0] || a[1] - b[1]);
      if (p.length < 3) return p;
      const cross = (o, a, b) => (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0]);
      const lower = [], upper = [];
      for (const q of p) { while (lower.length >= 2 && cross(lower[lower.length - 2], lower[lower.length - 1], q) <= 0) lower.pop(); lower.push(q); }
      for (const q of p.slice().reverse()) { while (upper.length >= 2 && cross(upper[upper.length - 2], upper[upper.length - 1], q) <= 0) upper.pop(); upper.push(q); }
      return lower.slice(0, -1).concat(upper.slice(0, -1));
    }

    function drawScene(k) {
      const g = canvas.getContext('2d');
      g.setTransform(dpr, 0, 0, dpr, 0, 0);
      g.clearRect(0, 0, W, H);
      g.lineJoin = 'round'; g.lineCap = 'round';
      // Guide lines of translational joints.
      joints.forEach((j) => {
        if (j.type !== 'translational' || !Array.isArray(j.axis)) return;
        const p = jointPoint(j.a, k);
        if (!p) return;
        let ax = j.axis;
        if (j.a.body !== 'ground' && pose(j.a.body, k)) {
          const q = pose(j.a.body, k);
          ax = [Math.cos(q[2]) * ax[0] - Math.sin(q[2]) * ax[1], Math.sin(q[2]) * ax[0] + Math.cos(q[2]) * ax[1]];
        }
        const n = Math.hypot(ax[0], ax[1]) || 1;
        const L = 4 * span;
        g.save(); g.strokeStyle = '#9aa3b2'; g.setLineDash([6, 4]); g.lineWidth = 1;
        g.beginPath();
        g.moveTo(X([p[0] - L * ax[0] / n, p[1] - L * ax[1] / n]), Y([p[0] - L * ax[0] / n, p[1] - L * ax[1] / n]));
        g.lineTo(X([p[0] + L * ax[0] / n, p[1] + L * ax[1] / n]), Y([p[0] + L * ax[0] / n, p[1] + L * ax[1] / n]));
        g.stroke(); g.restore();
      });
      // Ground markers: fixed triangles with hatching.
      groundMarkers.forEach((p) => {
        const cx = X(p), cy = Y(p);
        g.save(); g.fillStyle = '#e3e6ec'; g.strokeStyle = '#5d6677'; g.lineWidth = 1.2;
        g.beginPath(); g.moveTo(cx, cy); g.lineTo(cx - 10, cy + 16); g.lineTo(cx + 10, cy + 16); g.closePath();
        g.fill(); g.stroke();
        g.beginPath(); g.moveTo(cx - 15, cy + 16); g.lineTo(cx + 15, cy + 16); g.stroke();
        for (let h = -12; h <= 12; h += 6) { g.beginPath(); g.moveTo(cx + h, cy + 16); g.lineTo(cx + h - 5, cy + 22); g.stroke(); }
        g.restore();
      });
      // Bodies: convex shape / bar / block through their markers; the first body (usually the
      // driven one) last, on top.
      bodies.slice().reverse().forEach((b) => {
        const q = pose(b.name, k);
        if (!q) return;
        const color = bodyColor[b.name];
        const pts = markers[b.name].map((p) => world(q, p));
        g.save();
        if (flexible[b.name]) {
          // Ends A and B on the chord, control point 2w·mag off its middle (the parabola's
          // mid-point then lies w·mag off the chord).
          const fl = flexible[b.name], h = fl.length / 2, w = fl.w[k] * flexMag;
          const a = world(q, [-h, 0]), e = world(q, [h, 0]), c = world(q, [0, 2 * w]);
          g.strokeStyle = color; g.lineWidth = 9; g.globalAlpha = 0.85;
          g.beginPath(); g.moveTo(X(a), Y(a)); g.quadraticCurveTo(X(c), Y(c), X(e), Y(e)); g.stroke();
        } else if (pts.length >= 3) {
          const hull = convexHull(pts);
          g.beginPath(); hull.forEach((p, i) => (i ? g.lineTo(X(p), Y(p)) : g.moveTo(X(p), Y(p)))); g.closePath();
          g.fillStyle = color + '55'; g.strokeStyle = color; g.lineWidth = 2.5; g.fill(); g.stroke();
        } else if (pts.length === 2) {
          g.strokeStyle = color; g.lineWidth = 9; g.globalAlpha = 0.85;
          g.beginPath(); g.moveTo(X(pts[0]), Y(pts[0])); g.lineTo(X(pts[1]), Y(pts[1])); g.stroke();
        } else {
          const c = pts.length ? pts[0] : [q[0], q[1]];
          const hw = Math.max(24, 1.8 * (blockRadius[b.name] || 0) * scale), hh = Math.max(14, 1.35 * (blockRadius[b.name] || 0) * scale);
          g.translate(X(c), Y(c)); g.rotate(-q[2]);
          g.fillStyle = color + '40'; g.strokeStyle = color; g.lineWidth = 2;
          g.beginPath(); g.rect(-hw, -hh, 2 * hw, 2 * hh); g.fill(); g.stroke();
        }
        g.restore();
      });
      // Joints: pins, and bearing + journal circles at clearance joints.
      joints.forEach((j) => {
        if (j.type !== 'revolute') return;
        const pa = jointPoint(j.a, k), pb = jointPoint(j.b, k);
        if (!pa) return;
        g.save();
        if (j.clearance && pb) {
          const rb = Math.max(3, (j.clearance.bearing_radius || 0) * scale);
          const rj = Math.max(2, (j.clearance.journal_radius || 0) * scale);
          g.fillStyle = '#ffffff'; g.strokeStyle = bodyColor[j.b.body] || '#3a4252'; g.lineWidth = 2;
          g.beginPath(); g.arc(X(pb), Y(pb), rb, 0, 2 * Math.PI); g.fill(); g.stroke();
          g.fillStyle = (bodyColor[j.a.body] || '#3a4252') + 'aa'; g.strokeStyle = '#2b303b'; g.lineWidth = 1;
          g.beginPath(); g.arc(X(pa), Y(pa), rj, 0, 2 * Math.PI); g.fill(); g.stroke();
          const ins = insets.find((i) => i.joint === j);
          if (ins) {
            g.font = '600 12px system-ui, "DejaVu Sans", sans-serif'; g.fillStyle = '#1d2330';
            // Above-right of the bearing, or above-left where it would leave the canvas.
            const label = String(ins.tag) + '  ' + j.name, lw = g.measureText(label).width;
            const lx = X(pb) + rb + 4 + lw > W - 4 ? X(pb) - rb - 4 - lw : X(pb) + rb + 4;
            g.fillText(label, Math.max(4, lx), Math.max(14, Y(pb) - rb - 2));
          }
        } else {
          g.fillStyle = '#ffffff'; g.strokeStyle = '#2b303b'; g.lineWidth = 1.5;
          g.beginPath(); g.arc(X(pa), Y(pa), 4, 0, 2 * Math.PI); g.fill(); g.stroke();
        }
        g.restore();
      });
      // Body labels.
      g.save(); g.font = '11px system-ui, "DejaVu Sans", sans-serif'; g.fillStyle = '#5d6677';
      bodies.forEach((b) => {
        const q = pose(b.name, k);
        if (!q) return;
        // Below the lowest point of the body's shape.
        const pts = markers[b.name].map((p) => world(q, p));
        let low = Y(q) + (pts.length <= 1 ? Math.max(14, 1.35 * (blockRadius[b.name] || 0) * scale) : 6);
        pts.forEach((p) => { low = Math.max(low, Y(p) + 6); });
        const cx = pts.length ? pts.reduce((a, p) => a + X(p), 0) / pts.length : X(q);
        g.fillText(b.name, cx - g.measureText(b.name).width / 2, low + 12);
      });
      g.restore();
      // Scale bar.
      const bar = niceLength(span / 5);
      g.save(); g.strokeStyle = '#3a4252'; g.fillStyle = '#3a4252'; g.lineWidth = 1.5;
      const bx = 12, by = H - 14;
      g.beginPath(); g.moveTo(bx, by); g.lineTo(bx + bar * scale, by);
      g.moveTo(bx, by - 4); g.lineTo(bx, by + 4); g.moveTo(bx + bar * scale, by - 4); g.lineTo(bx + bar * scale, by + 4); g.stroke();
      g.font = '11px system-ui, "DejaVu Sans", sans-serif';
      g.fillText(fmt(bar * 1e3) + ' mm', bx + bar * scale + 6, by + 4);
      g.restore();
    }
    function niceLength(v) {
      const e = Math.pow(10, Math.floor(Math.log10(v)));
      const m = v / e;
      return (m >= 5 ? 5 : m >= 2 ? 2 : 1) * e;
    }

    const TRAIL = 40;   // frames of history behind the journal centre
    const lowerIndex = (ts, t) => {
      let lo = 0, hi = ts.length - 1;
      while (lo < hi) { const m = (lo + hi + 1) >> 1; if (ts[m] <= t) lo = m; else hi = m - 1; }
      return lo;
    };
    function drawInset(ins, k) {
      const g = ins.canvas.getContext('2d');
      const w = ins.w, h = ins.h;
      g.setTransform(dpr, 0, 0, dpr, 0, 0);
      g.clearRect(0, 0, w, h);
      const c = ins.joint.clearance.clearance || maxAbsOf([ins.ecc.map((e) => Math.hypot(e[0], e[1]))]) || 1;
      const R = Math.min(w, h) / 2 - 26;
      const s = R / (1.15 * c);
      const cx = w / 2, cy = h / 2 + 4;
      const P = (e) => [cx + e[0] * s, cy - e[1] * s];
      const modeAt = (j) => {
        if (ins.mode) return ins.mode(F.time[j]);
        const e = ins.ecc[j];
        return Math.hypot(e[0], e[1]) >= c ? 'contact' : 'free';
      };
      // Crosshair, half-clearance ring and the clearance circle.
      g.strokeStyle = '#e1e4ea'; g.lineWidth = 1;
      g.beginPath(); g.moveTo(cx - 1.15 * c * s, cy); g.lineTo(cx + 1.15 * c * s, cy);
      g.moveTo(cx, cy - 1.15 * c * s); g.lineTo(cx, cy + 1.15 * c * s); g.stroke();
      g.setLineDash([3, 3]); g.beginPath(); g.arc(cx, cy, 0.5 * c * s, 0, 2 * Math.PI); g.stroke(); g.setLineDash([]);
      g.strokeStyle = '#3a4252'; g.lineWidth = 1.5;
      g.beginPath(); g.arc(cx, cy, c * s, 0, 2 * Math.PI); g.stroke();
      // Trail over the last TRAIL frames, coloured by mode and fading out.
      const k0 = Math.max(0, k - TRAIL);
      const modeAtT = (t, e) => (ins.mode ? ins.mode(t) : (Math.hypot(e[0], e[1]) >= c ? 'contact' : 'free'));
      let pts;
      if (ins.trail) {
        const T = ins.trail, i0 = lowerIndex(T.t, F.time[k0]), i1 = lowerIndex(T.t, F.time[k]);
        pts = [];
        for (let i = i0; i <= i1; i++) pts.push({t: T.t[i], e: [T.x[i], T.y[i]]});
      } else pts = ins.ecc.slice(k0, k + 1).map((e, i) => ({t: F.time[k0 + i], e: e}));
      pts.push({t: F.time[k], e: ins.ecc[k]});
      g.lineWidth = 1.6;
      for (let i = 1; i < pts.length; i++) {
        const a = P(pts[i - 1].e), b = P(pts[i].e);
        g.globalAlpha = 0.12 + 0.88 * i / pts.length;
        g.strokeStyle = MODE_COLOR[modeAtT(pts[i].t, pts[i].e)];
        g.beginPath(); g.moveTo(a[0], a[1]); g.lineTo(b[0], b[1]); g.stroke();
      }
      g.globalAlpha = 1;
      const e = ins.ecc[k], m = modeAt(k), p = P(e);
      g.fillStyle = MODE_COLOR[m]; g.strokeStyle = '#fff'; g.lineWidth = 1.5;
      g.beginPath(); g.arc(p[0], p[1], 5, 0, 2 * Math.PI); g.fill(); g.stroke();
      // Text: mode, eccentricity, magnification.
      const en = Math.hypot(e[0], e[1]);
      g.font = '600 11px system-ui, "DejaVu Sans", sans-serif'; g.fillStyle = MODE_COLOR[m];
      g.fillText(MODE_LABEL[m], 6, 13);
      g.font = '11px system-ui, "DejaVu Sans", sans-serif'; g.fillStyle = '#5d6677';
      const pen = (en - c) * 1e6;
      g.fillText('e/c = ' + (en / c).toFixed(3) + (pen > 0 ? ',  δ = ' + pen.toFixed(1) + ' µm' : ''), 6, h - 8);
      const tx = 'c = ' + fmt(c * 1e3) + ' mm';
      g.fillText(tx, w - 6 - g.measureText(tx).width, 13);
      ins.title.replaceChildren(ins.tag + '  ' + ins.joint.name + '  ',
        el('span', {class: 'muted', style: 'font-weight:400', text: 'magnified ×' + fmt(s / scale, 2)}));
    }

    let frame = 0, playing = false, last = null, acc = 0;
    function show(k) {
      frame = Math.max(0, Math.min(nFrames - 1, k));
      drawScene(frame);
      insets.forEach((ins) => drawInset(ins, frame));
      slider.value = String(frame);
      const t = F.time[frame];
      const th = crankAt(t);
      readout.textContent = 't = ' + (t * 1e3).toFixed(3) + ' ms' + (isNum(th) ? '   θ = ' + th.toFixed(1) + '°' : '');
    }
    function tick(now) {
      if (!playing) return;
      if (last !== null) {
        acc += (now - last) / 1000 * 60 * parseFloat(speed.value);
        const steps = Math.floor(acc);
        if (steps > 0) { acc -= steps; show((frame + steps) % nFrames); }
      }
      last = now;
      requestAnimationFrame(tick);
    }
    function setPlaying(on) {
      playing = on; last = null; acc = 0;
      play.textContent = on ? '❚❚ Pause' : '▶ Play';
      if (on) requestAnimationFrame(tick);
    }
    play.addEventListener('click', () => setPlaying(!playing));
    slider.addEventListener('input', () => { setPlaying(false); show(parseInt(slider.value, 10)); });
    resize(); show(0);
    window.addEventListener('resize', () => { resize(); show(frame); });
    report.animation = {canvas: canvas, frames: nFrames, show: show, setPlaying: setPlaying,
                        frame: () => frame};
    report.insets = insets.map((i) => i.canvas);
  }

  // --- time series --------------------------------------------------------------------------------
  const GROUPS = [
    {key: 'bodies', title: 'Bodies', note: 'positions, velocities and accelerations of the centres of mass'},
    {key: 'joints', title: 'Joints', note: 'reaction forces of the ideal joints'},
    {key: 'clearance', title: 'Clearance joints', note: 'eccentricity, penetration, contact forces; mode 0 = free flight, 1 = contact'},
    {key: 'drivers', title: 'Drivers', note: 'driving torques and forces'},
    {key: 'energy', title: 'Energy and constraints', note: 'energy.balance = kinetic + potential + dissipated − input'},
    {key: 'other', title: 'Other channels', note: ''},
  ];
  function groupOf(name) {
    const [e, q] = splitChannel(name);
    if (e === 'energy' || e === 'constraint') return 'energy';
    if (clearanceJoints.some((j) => j.name === e)) return 'clearance';
    if (joints.some((j) => j.name === e)) return 'joints';
    const isBody = bodies.some((b) => b.name === e);
    if (isBody && BODY_QUANTITIES.has(q)) return 'bodies';
    if (drivers.some((d) => d.name === e)) return 'drivers';
    if (isBody) return 'bodies';
    return 'other';
  }
  function defaultSelection(group, names) {
    const pick = (cands) => cands.filter((n) => names.includes(n));
    let sel = [];
    if (group === 'bodies') {
      const last = bodies.length ? bodies[bodies.length - 1].name : '';
      sel = pick([last + '.ax']);
    } else if (group === 'joints') sel = names.filter((n) => splitChannel(n)[1] === 'F');
    else if (group === 'clearance') sel = names.filter((n) => splitChannel(n)[1] === 'Fn');
    else if (group === 'energy') sel = names.filter((n) => splitChannel(n)[0] === 'energy');
    else if (group === 'drivers') sel = names.slice(0, 3);
    return sel.length ? sel : names.slice(0, 1);
  }
  function unwrapDegrees(a) {
    const out = new Array(a.length);
    let off = 0;
    for (let i = 0; i < a.length; i++) {
      if (!isNum(a[i])) { out[i] = null; continue; }
      if (i > 0 && isNum(a[i - 1]) && a[i] - a[i - 1] < -180) off += 360;
      out[i] = a[i] + off;
    }
    return out;
  }

  function renderTimeSeries() {
    const s = section('timeseries', 'Time series', 'Time series');
    const t = series.time;
    if (!Array.isArray(t) || !t.length || isEmptyObj(channels)) { notComputed(s, 'series'); return; }
    const hasCrank = Array.isArray(series.crank_angle) && series.crank_angle.length === t.length;
    const crankX = hasCrank ? unwrapDegrees(series.crank_angle) : null;
    let xMode = 'time';
    const hasIdeal = !isEmptyObj(series.ideal);
    let showIdeal = hasIdeal;
    const xswitch = el('div', {class: 'xswitch'},
      el('label', {title: hasIdeal ? 'overlay the ideal twin (all joints ideal), dashed' : 'no ideal twin in this report'},
        el('input', {type: 'checkbox', id: 'show-ideal', checked: hasIdeal ? true : null, disabled: !hasIdeal,
                     onchange: (ev) => { showIdeal = ev.target.checked; redrawAll(); }}), ' ideal twin'),
      el('span', {class: 'muted', style: 'margin-left:10px', text: 'x axis:'}),
      el('label', {}, el('input', {type: 'radio', name: 'xaxis', value: 'time', checked: true}), ' time'),
      el('label', {title: hasCrank ? 'crank angle, unwrapped over revolutions' : 'no rotary driver in this model'},
        el('input', {type: 'radio', name: 'xaxis', value: 'crank', disabled: !hasCrank}), ' crank angle'));
    s.querySelector('.card-head').append(xswitch);
    s.append(el('p', {class: 'legend-note', text:
      'Drag to zoom, double-click to reset; click a legend entry to hide it. ' +
      (hasIdeal ? 'Dark dashed lines: the ideal twin (all joints ideal) on the same time base. ' : '') +
      'Values are decimated for display; full data in timeseries.csv.' +
      (hasChannelInfo ? '' : ' This report carries no channel units (no channel_info in its data): units show as –.')}));

    const groups = {};
    Object.keys(channels).forEach((n) => { const g = groupOf(n); (groups[g] = groups[g] || []).push(n); });
    const charts = [];
    GROUPS.forEach((G) => {
      const names = groups[G.key];
      if (!names || !names.length) return;
      const box = el('div', {class: 'group'});
      const selected = new Set(defaultSelection(G.key, names));
      // Picker: one row per element, one checkbox per quantity.
      const picker = el('div', {class: 'picker'});
      const byElement = {};
      names.forEach((n) => { const [e] = splitChannel(n); (byElement[e] = byElement[e] || []).push(n); });
      const block = chartBlock('', 'ts-' + G.key);
      Object.entries(byElement).forEach(([e, list]) => {
        picker.append(el('span', {class: 'el', text: e}), el('span', {}, list.map((n) =>
          el('label', {title: n + ': ' + descriptionOf(n) + ' [' + unitText(unitOf(n)) + ']' + (ideal[n] ? ', with ideal twin' : ''),
                       'data-channel': n},
            el('input', {type: 'checkbox', value: n, checked: selected.has(n) ? true : null,
              onchange: (ev) => { if (ev.target.checked) selected.add(n); else selected.delete(n); draw(); }}),
            splitChannel(n)[1]))));
      });
      box.append(el('div', {class: 'group-head'}, el('h3', {text: G.title}),
        el('span', {class: 'tools'}, el('span', {class: 'legend-note', text: G.note}), block.button)), picker, block.node);
      s.append(box);
      const draw = () => drawGroupChart(block.holder, 'ts-' + G.key, names.filter((n) => selected.has(n)));
      charts.push(draw);
    });

    function drawGroupChart(holder, id, sel) {
      if (!sel.length) {
        holder.replaceChildren(el('p', {class: 'not-computed', text: 'no channel selected'}));
        report.charts = report.charts.filter((c) => c.id !== id);
        return;
      }
      const xs = xMode === 'crank' ? crankX : t;
      const xScale = xMode === 'crank' ? {f: 1, unit: '°'} : displayScale('s', maxAbsOf([t]));
      // One y scale per unit, in order of first appearance; the first two get an axis each side.
      const units = [];
      sel.forEach((n) => { const u = unitOf(n) || '–'; if (!units.includes(u)) units.push(u); });
      const scaleOf = {};
      units.forEach((u) => {
        const arrays = sel.filter((n) => (unitOf(n) || '–') === u).flatMap((n) => [channels[n], showIdeal ? ideal[n] : null]);
        scaleOf[u] = displayScale(u === '–' ? '' : u, maxAbsOf(arrays));
      });
      const data = [xs];
      const ser = [{label: xMode === 'crank' ? 'θ [°]' : 't [' + xScale.unit + ']',
                    value: (u, v) => (v == null ? '–' : fmtTick(+(v * xScale.f).toPrecision(6)))}];
      sel.forEach((n, i) => {
        const u = unitOf(n) || '–';
        const color = PALETTE[i % PALETTE.length];
        const sc = scaleOf[u];
        const value = (uu, v) => (v == null ? '–' : fmt(v * sc.f));
        data.push(channels[n]);
        ser.push({label: n + ' [' + unitText(sc.unit) + ']', stroke: color, width: 1.3, scale: u, value: value,
                  points: {show: false}});
        if (showIdeal && ideal[n]) {
          data.push(ideal[n]);
          ser.push({label: n + ' ideal', stroke: shade(color, 0.55), width: 1.5, dash: [6, 3], scale: u, value: value,
                    points: {show: false}});
        }
      });
      const axes = [axis({scale: 'x', side: 2, f: xScale.f, label: xMode === 'crank' ? 'crank angle [°]' : 'time [' + xScale.unit + ']'})];
      units.forEach((u, k) => {
        axes.push(axis({scale: u, side: k === 1 ? 1 : 3, f: scaleOf[u].f, label: '[' + unitText(scaleOf[u].unit) + ']',
                        grid: k === 0 ? GRID : {show: false}}));
      });
      const scales = {x: {time: false}};
      if (xMode === 'crank') scales.x.range = (u, mn, mx) => [mn, mx];
      units.forEach((u) => { scales[u] = {auto: true}; });
      if (xMode === 'crank') axes[0].incrs = [1, 5, 10, 15, 30, 45, 90, 180, 360, 720, 1440, 2880, 5760];
      makeChart(holder, id, {
        height: 250, series: ser, axes: axes, scales: scales,
        cursor: {sync: {key: 'lash-' + xMode}, drag: {x: true, y: false}, points: {size: 5}},
        legend: {live: true},
      }, data);
    }
    function redrawAll() { charts.forEach((d) => d()); }
    s.querySelectorAll('input[name=xaxis]').forEach((r) => r.addEventListener('change', (ev) => {
      xMode = ev.target.value; redrawAll();
    }));
    redrawAll();
  }

  // --- statistics and comparison ------------------------------------------------------------------
  function renderStatistics() {
    let holder = null;
    const s = section('statistics', 'Statistics', 'Statistics', copyButton(() => holder.querySelector('table')));
    holder = el('div'); s.append(holder);
    const st = analysis.statistics;
    if (isEmptyObj(st)) notComputed(holder);
    else {
      const rows = Object.values(st);
      const exact = rows.filter((v) => v && v.extrema === 'exact').length;
      holder.append(el('p', {class: 'legend-note', text: exact === rows.length
        ? 'min, max and peak are exact: tracked between outputs on the integrator\'s dense output, ' +
          'independent of the output interval; RMS and crest factor use the output samples.'
        : 'min, max and peak over a crank-angle range come from the output samples (exact only over time windows).'}));
      holder.append(table(['channel', 'description', 'unit', 'min', 'max', 'peak', 'at [ms]', 'rms', 'crest factor', 'window [ms]'],
        Object.entries(st).map(([n, v]) => [n, descriptionOf(n), unitText(unitOf(n)), fmt(v.min), fmt(v.max), fmt(v.peak),
          isNum(v.t_max) && isNum(v.t_min) ? fmt((Math.abs(v.max) >= Math.abs(v.min) ? v.t_max : v.t_min) * 1e3) : '–',
          fmt(v.rms), fmt(v.crest, 3), Array.isArray(v.window) ? fmt(v.window[0] * 1e3) + ' – ' + fmt(v.window[1] * 1e3) : '–']),
        [3, 4, 5, 6, 7, 8, 9]));
    }
    let holder2 = null;
    const c = section('comparison', 'Comparison with the ideal twin', 'Ideal comparison',
      copyButton(() => holder2.querySelector('table')));
    holder2 = el('div'); c.append(holder2);
    const cmp = analysis.comparison;
    if (isEmptyObj(cmp)) { notComputed(holder2); return; }
    holder2.append(el('p', {class: 'legend-note', text:
      'peak ratio = peak with clearance / peak of the ideal twin; deviations are clearance − ideal on the same time base.'}));
    holder2.append(table(['channel', 'unit', 'ideal peak', 'peak ratio', 'rms deviation', 'max deviation'],
      Object.entries(cmp).map(([n, v]) => [n, unitText(unitOf(n)), fmt(v.ideal_peak), fmt(v.peak_ratio, 3),
        fmt(v.rms_deviation), fmt(v.max_deviation)]), [2, 3, 4, 5]));
  }

  // --- clearance joints: orbit, modes, episodes strip, impact velocities ---------------------------
  function circleHook(radius, color) {
    return (u) => {
      if (!isNum(radius) || radius <= 0) return;
      const g = u.ctx;
      const cx = u.valToPos(0, 'x', true), cy = u.valToPos(0, 'y', true);
      const rx = Math.abs(u.valToPos(radius, 'x', true) - cx), ry = Math.abs(u.valToPos(radius, 'y', true) - cy);
      g.save();
      g.beginPath(); g.rect(u.bbox.left, u.bbox.top, u.bbox.width, u.bbox.height); g.clip();
      g.strokeStyle = color || '#3a4252'; g.lineWidth = 1.5 * devicePixelRatio;
      g.beginPath(); g.ellipse(cx, cy, rx, ry, 0, 0, 2 * Math.PI); g.stroke();
      g.restore();
    };
  }
  function xyChart(holder, id, xs, ys, opt) {
    const xsc = displayScale(opt.xUnit, maxAbsOf([xs]).valueOf() || opt.extent || 0);
    const ysc = displayScale(opt.yUnit, maxAbsOf([ys]).valueOf() || opt.extent || 0);
    const scales = {x: {time: false, auto: !opt.range}, y: {auto: !opt.range}};
    if (opt.range) { scales.x.range = opt.range; scales.y.range = opt.range; }
    const height = opt.height || 320;
    return makeChart(holder, id, {
      mode: 2, height: height,
      scales: scales,
      axes: [axis({scale: 'x', side: 2, f: xsc.f, label: opt.xLabel + ' [' + unitText(xsc.unit) + ']'}),
             axis({scale: 'y', side: 3, f: ysc.f, label: opt.yLabel + ' [' + unitText(ysc.unit) + ']'})],
      series: [{}, {label: opt.label, stroke: opt.color || PALETTE[0], width: opt.dots ? 0 : 1.1,
                    paths: opt.dots ? xyDotPaths : xyLinePaths, points: {show: false},
                    facets: [{scale: 'x', auto: !opt.range}, {scale: 'y', auto: !opt.range}]}],
      legend: {show: false},
      cursor: {drag: {x: true, y: true, uni: 20}, points: {show: false}, dataIdx: () => null},
      hooks: opt.hooks || {},
    }, [null, [xs, ys]], !!opt.square);
  }

  function renderClearance() {
    const s = section('clearance', 'Clearance joints', 'Clearance joints');
    const C = analysis.clearance;
    if (isEmptyObj(C)) { notComputed(s); return; }
    const tEnd = Array.isArray(series.time) && series.time.length ? series.time[series.time.length - 1]
                 : (model.solver || {}).end_time;
    Object.entries(C).forEach(([name, J]) => {
      if (!J) return;
      const box = el('div', {class: 'group'});
      box.append(el('h3', {text: name + (isNum(J.clearance) ? '   (clearance c = ' + fmt(J.clearance * 1e3) + ' mm)' : '')}));
      const grid = el('div', {class: 'grid2'});
      // Orbit.
      const left = el('div');
      const orbit = J.orbit;
      if (orbit && Array.isArray(orbit.ex) && orbit.ex.length) {
        const b = chartBlock('Journal centre orbit', 'orbit-' + name,
          'journal centre relative to the bearing centre; circle: e = c, where contact begins');
        left.append(b.node);
        const ext = 1.2 * Math.max(J.clearance || 0, maxAbsOf([orbit.ex, orbit.ey]));
        box._draw = box._draw || [];
        box._draw.push(() => xyChart(b.holder, 'orbit-' + name, orbit.ex, orbit.ey, {
          xUnit: 'm', yUnit: 'm', xLabel: name + '.ex', yLabel: name + '.ey', label: 'orbit', color: PALETTE[0],
          range: () => [-ext, ext], extent: ext, square: true, height: 340,
          hooks: {draw: [circleHook(J.clearance, '#3a4252')]}}));
      } else notComputed(left, 'orbit');
      grid.append(left);
      // Modes, episodes, histogram.
      const right = el('div');
      const M = J.modes;
      right.append(el('div', {class: 'chart-title', text: 'Contact modes'}));
      if (M) {
        const shares = [['free', M.free_flight_share], ['impact', M.impact_share], ['continuous', M.continuous_share]];
        right.append(el('div', {class: 'shares'}, shares.map(([m, v]) =>
          el('div', {style: 'width:' + (100 * (isNum(v) ? v : 0)).toFixed(3) + '%;background:' + MODE_COLOR[m],
                     title: MODE_LABEL[m] + ': ' + (isNum(v) ? (100 * v).toFixed(1) + ' %' : '–')}))));
        right.append(el('div', {class: 'share-key'}, shares.map(([m, v]) => el('span', {},
          el('i', {style: 'background:' + MODE_COLOR[m]}), MODE_LABEL[m] + ' ' + (isNum(v) ? (100 * v).toFixed(1) + ' %' : '–')))));
        right.append(el('p', {class: 'muted', style: 'margin:6px 0 0',
          text: fmtInt(M.impacts) + ' impacts · continuous contact ' + (isNum(M.continuous_contact_time)
            ? fmt(M.continuous_contact_time * 1e3) + ' ms' : '–')}));
        if (Array.isArray(M.episodes) && isNum(tEnd)) {
          const strip = el('canvas', {class: 'strip', 'data-joint': name});
          right.append(el('div', {class: 'chart-title', style: 'margin-top:10px', text: 'Mode along time'}), strip);
          box._draw = box._draw || [];
          box._draw.push(() => drawStrip(strip, M.episodes, series.time ? series.time[0] : 0, tEnd));
        }
      } else notComputed(right, 'modes');
      // Impact velocity histogram.
      let hist = J.histogram;
      const vel = Array.isArray(J.impact_velocities) ? J.impact_velocities.filter(isNum) : null;
      if ((!hist || !Array.isArray(hist.edges)) && vel && vel.length) hist = histogram(vel, 12);
      if (hist && Array.isArray(hist.edges) && Array.isArray(hist.counts) && hist.counts.length) {
        const b = chartBlock('Impact velocities', 'hist-' + name,
          (vel ? vel.length + ' onsets; ' : '') + 'δ̇⁻: approach speed at the located contact onset' +
          (vel && vel.length ? ' (max ' + fmt(Math.max(...vel), 3) + ' m/s)' : ''));
        right.append(b.node);
        box._draw = box._draw || [];
        box._draw.push(() => drawHistogram(b.holder, 'hist-' + name, hist));
      } else notComputed(right, 'impact velocities');
      grid.append(right);
      box.append(grid);
      s.append(box);
      (box._draw || []).forEach((f) => f());
    });
  }
  function histogram(values, bins) {
    const mx = Math.max(...values), mn = Math.min(0, ...values);
    const w = (mx - mn) / bins || 1;
    const edges = Array.from({length: bins + 1}, (_, i) => mn + i * w);
    const counts = new Array(bins).fill(0);
    values.forEach((v) => { counts[Math.min(bins - 1, Math.floor((v - mn) / w))]++; });
    return {edges: edges, counts: counts};
  }
  function drawHistogram(holder, id, hist) {
    const n = hist.counts.length;
    const centers = hist.counts.map((_, i) => (hist.edges[i] + hist.edges[i + 1]) / 2);
    const xsc = displayScale('m/s', maxAbsOf([hist.edges]));
    makeChart(holder, id, {
      height: 200,
      scales: {x: {time: false, range: () => [hist.edges[0], hist.edges[n]]}, y: {range: (u, mn, mx) => [0, Math.max(1, mx) * 1.1]}},
      axes: [axis({scale: 'x', side: 2, f: xsc.f, label: 'impact velocity δ̇⁻ [' + xsc.unit + ']'}),
             axis({scale: 'y', side: 3, label: 'count', values: (u, sp) => sp.map((v) => (Number.isInteger(v) ? String(v) : ''))})],
      series: [{label: 'δ̇⁻', value: (u, v) => fmt(v)},
               {label: 'impacts', stroke: MODE_COLOR.impact, fill: MODE_COLOR.impact + 'aa', width: 1,
                paths: uPlot.paths.bars({size: [0.92, Infinity], align: 0}), points: {show: false}}],
      legend: {show: false}, cursor: {drag: {x: false, y: false}},
    }, [centers, hist.counts]);
  }
  function drawStrip(canvas, episodes, t0, t1) {
    const dpr = window.devicePixelRatio || 1;
    const w = canvas.getBoundingClientRect().width || 400, h = 54;
    canvas.width = Math.round(w * dpr); canvas.height = Math.round(h * dpr);
    const g = canvas.getContext('2d');
    g.setTransform(dpr, 0, 0, dpr, 0, 0);
    const L = 8, R = w - 8, top = 4, bh = 22;
    const X = (t) => L + (t - t0) / (t1 - t0 || 1) * (R - L);
    g.fillStyle = MODE_COLOR.free; g.fillRect(L, top, R - L, bh);
    episodes.forEach((e) => {
      const k = e[2] === 'impact' ? 'impact' : 'continuous';
      g.fillStyle = MODE_COLOR[k];
      g.fillRect(X(e[0]), top, Math.max(1, X(e[1]) - X(e[0])), bh);
    });
    // Time axis in ms.
    const sc = displayScale('s', Math.abs(t1));
    g.strokeStyle = '#3a4252'; g.fillStyle = '#3a4252'; g.font = '10.5px system-ui, "DejaVu Sans", sans-serif';
    g.beginPath(); g.moveTo(L, top + bh + 0.5); g.lineTo(R, top + bh + 0.5); g.stroke();
    const span = (t1 - t0) * sc.f;
    const step = [1, 2, 5, 10, 20, 50, 100, 200, 500].map((m) => m * Math.pow(10, Math.floor(Math.log10(span)) - 1))
      .find((st) => span / st <= 8) || span;
    for (let v = Math.ceil(t0 * sc.f / step) * step; v <= t1 * sc.f + 1e-9; v += step) {
      const x = X(v / sc.f);
      g.beginPath(); g.moveTo(x, top + bh); g.lineTo(x, top + bh + 4); g.stroke();
      const txt = fmtTick(+v.toPrecision(6));
      g.fillText(txt, Math.min(Math.max(L, x - g.measureText(txt).width / 2), R - g.measureText(txt).width), top + bh + 15);
    }
    g.fillText('time [' + sc.unit + ']', R - 60, top + bh + 27);
  }

  // --- Poincaré, spectra, phase portraits, Lyapunov, verdict -----------------------------------------
  function renderPoincare() {
    const s = section('poincare', 'Poincaré section', 'Poincaré');
    const P = analysis.poincare;
    if (!P || !Array.isArray(P.points) || !P.points.length) { notComputed(s); return; }
    const vars = Array.isArray(P.variables) ? P.variables : ['x', 'y'];
    const info = [];
    if (P.kind) info.push(P.kind + ' section');
    if (isNum(P.period)) info.push('period T = ' + fmt(P.period * 1e3) + ' ms');
    if (isNum(P.discarded_periods)) info.push(P.discarded_periods + ' period(s) discarded as transient');
    info.push(P.points.length + ' points');
    if (isNum(P.distinct)) info.push(P.distinct + ' distinct');
    const grid = el('div', {class: 'grid2'});
    const b = chartBlock(vars[0] + ' vs ' + vars[1], 'poincare');
    grid.append(el('div', {}, b.node));
    grid.append(el('div', {}, el('p', {class: 'muted', text: info.join(' · ')}),
      el('p', {class: 'legend-note', text: 'One point per period: a periodic response gives one point (or k for a ' +
        'period-k orbit), a quasi-periodic one a closed curve, a chaotic one a scattered set.'})));
    s.append(grid);
    sectionChart(b.holder, 'poincare', P.points, vars);
    // Every other clearance joint's eccentricity at the same section times.
    const others = (Array.isArray(P.joints) ? P.joints : []).filter((j) => j && Array.isArray(j.points) &&
      j.points.length && Array.isArray(j.variables) && j.variables.length === 2 &&
      !(j.variables[0] === vars[0] && j.variables[1] === vars[1]));
    if (others.length) {
      const more = el('div', {class: 'grid2'});
      s.append(more);
      others.forEach((j, k) => {
        const jb = chartBlock(j.variables[0] + ' vs ' + j.variables[1], 'poincare-' + k,
          j.points.length + ' points' + (isNum(j.distinct) ? ' · ' + j.distinct + ' distinct' : ''));
        more.append(el('div', {}, jb.node));
        sectionChart(jb.holder, 'poincare-' + k, j.points, j.variables);
      });
    }
  }

  /** One set of Poincaré points over two channels, with the clearance circle on an eccentricity. */
  function sectionChart(holder, id, points, vars) {
    const xs = points.map((p) => p[0]), ys = points.map((p) => p[1]);
    const [je, jq] = splitChannel(vars[0]);
    const cj = clearanceJoints.find((j) => j.name === je);
    const onEcc = cj && jq === 'ex';
    const ext = onEcc ? 1.2 * Math.max(cj.clearance.clearance, maxAbsOf([xs, ys])) : null;
    xyChart(holder, id, xs, ys, {
      xUnit: unitOf(vars[0]), yUnit: unitOf(vars[1]), xLabel: vars[0], yLabel: vars[1], label: 'Poincaré points',
      color: PALETTE[1], dots: true, square: true, height: 340,
      range: onEcc ? () => [-ext, ext] : null, extent: ext,
      hooks: onEcc ? {draw: [circleHook(cj.clearance.clearance, '#9aa3b2')]} : {}});
  }

  function renderSpectra() {
    const s = section('spectra', 'Spectra', 'Spectra');
    const S = analysis.spectra;
    if (isEmptyObj(S)) { notComputed(s); return; }
    const names = Object.keys(S).filter((n) => S[n] && Array.isArray(S[n].frequency));
    if (!names.length) { notComputed(s); return; }
    const pick = el('select', {id: 'spectrum-select'}, names.map((n) => el('option', {value: n, text: n})));
    s.querySelector('.card-head').append(el('label', {class: 'xswitch'}, 'channel ', pick));
    const info = el('p', {class: 'legend-note'});
    const b = chartBlock('Amplitude spectrum', 'spectrum');
    s.append(info, b.node);
    const draw = () => {
      const n = pick.value, sp = S[n];
      const amp = sp.amplitude.map((v) => (isNum(v) && v > 0 ? v : null));
      const f = sp.frequency;
      const fs = displayScale('Hz', maxAbsOf([f]));
      const u = unitOf(n);
      info.textContent = 'Single-sided amplitude spectrum of ' + n + (sp.window ? ', ' + sp.window + ' window' : '') +
        (isNum(sp.discarded_time) ? ', first ' + fmt(sp.discarded_time * 1e3) + ' ms discarded as transient' : '') +
        (isNum(model.drivers && drivers[0] && drivers[0].speed) ? '; crank frequency ' + fmt(drivers[0].speed / (2 * Math.PI)) + ' Hz' : '') + '.';
      makeChart(b.holder, 'spectrum', {
        height: 260,
        scales: {x: {time: false}, y: {distr: 3, log: 10}},
        axes: [axis({scale: 'x', side: 2, f: fs.f, label: 'frequency [' + fs.unit + ']'}),
               axis({scale: 'y', side: 3, label: 'amplitude [' + unitText(u) + ']', values: (uu, sp2) => sp2.map(logTick)})],
        series: [{label: 'f [' + fs.unit + ']', value: (uu, v) => (v == null ? '–' : fmt(v * fs.f))},
                 {label: n + ' [' + unitText(u) + ']', stroke: PALETTE[0], width: 1.2, points: {show: false},
                  value: (uu, v) => fmt(v)}],
        cursor: {drag: {x: true, y: false}, points: {size: 5}},
        legend: {live: true},
      }, [f, amp]);
    };
    pick.addEventListener('change', draw);
    draw();
  }

  /** Log-axis tick: decades only, as 10ⁿ (1 and 10 plain). */
  function logTick(v) {
    if (!isNum(v) || v <= 0) return '';
    const e = Math.round(Math.log10(v));
    if (Math.abs(v / Math.pow(10, e) - 1) > 1e-6) return '';
    return e === 0 ? '1' : e === 1 ? '10' : '10' + sup(e);
  }

  function renderPhase() {
    const s = section('phase', 'Phase portraits', 'Phase portraits');
    const P = analysis.phase;
    if (!Array.isArray(P) || !P.length) { notComputed(s); return; }
    const grid = el('div', {class: 'grid2'});
    s.append(grid);
    let drawn = 0;
    P.forEach((pair, i) => {
      if (!pair) return;
      const xs = channels[pair.x], ys = channels[pair.y];
      const cell = el('div');
      grid.append(cell);
      if (!xs || !ys) { notComputed(cell, (pair.x || '?') + ' vs ' + (pair.y || '?') + ' (channel missing)'); return; }
      const id = 'phase-' + i;
      const b = chartBlock(pair.y + ' vs ' + pair.x, id);
      cell.append(b.node);
      xyChart(b.holder, id, xs, ys, {xUnit: unitOf(pair.x), yUnit: unitOf(pair.y), xLabel: pair.x, yLabel: pair.y,
        label: pair.y + ' vs ' + pair.x, color: PALETTE[(i + 2) % PALETTE.length], height: 300});
      drawn++;
    });
    if (!drawn && !grid.children.length) notComputed(s);
  }

  function renderLyapunov() {
    const s = section('lyapunov', 'Lyapunov exponents', 'Lyapunov');
    const L = analysis.lyapunov;
    if (!L) { notComputed(s); return; }
    const unit = L.unit || '1/s';
    const method = L.method === 'variational' ? 'variational equations with saltation matrices at contact events'
      : (L.method === 'two-trajectory' ? 'two trajectories, d0 = ' + fmt(L.d0, 3) + ' m' : null);
    s.append(el('p', {}, el('span', {class: 'big-number', text: 'λ₁ ≈ ' + fmt(L.exponent, 3) + ' ' + unit}),
      el('span', {class: 'muted', text: '   ' + [method, isNum(L.renormalisations) ? L.renormalisations + ' renormalisations' : null,
        isNum(L.interval) ? 'every ' + fmt(L.interval * 1e3) + ' ms' : null,
        isNum(L.events_mapped) ? L.events_mapped + ' contact events mapped' : null].filter(Boolean).join(', ')})));
    const spectrum = Array.isArray(L.spectrum) ? L.spectrum : null;
    if (spectrum) s.append(el('p', {text: 'Spectrum: ' + spectrum.map((v, k) => 'λ' + (k + 1) + ' = ' + fmt(v, 4)).join(', ') + ' ' + unit}));
    // Running estimates: every exponent of the spectrum, or the largest alone.
    const SH = Array.isArray(L.spectrum_history) && L.spectrum_history.length ? L.spectrum_history : null;
    const H = SH || L.history;
    if (!Array.isArray(H) || !H.length) { notComputed(s, 'history'); return; }
    const ts = H.map((h) => h[0]);
    const count = SH ? SH[0].length - 1 : 1;
    const columns = [];
    for (let k = 0; k < count; k++) columns.push(H.map((h) => h[k + 1]));
    const tsc = displayScale('s', maxAbsOf([ts]));
    const b = chartBlock('Running estimates', 'lyapunov', 'a positive limit of λ₁ indicates chaos, zero a periodic or quasi-periodic motion');
    s.append(b.node);
    const series = [{label: 't [' + tsc.unit + ']', value: (u, v) => (v == null ? '–' : fmt(v * tsc.f))}];
    for (let k = 0; k < count; k++)
      series.push({label: 'λ' + (k + 1) + ' [' + unit + ']', stroke: PALETTE[(4 + k) % PALETTE.length], width: 1.4, points: {show: false}, value: (u, v) => fmt(v)});
    makeChart(b.holder, 'lyapunov', {
      height: 230,
      scales: {x: {time: false}, y: {auto: true}},
      axes: [axis({scale: 'x', side: 2, f: tsc.f, label: 'time [' + tsc.unit + ']'}),
             axis({scale: 'y', side: 3, label: 'estimate [' + unit + ']'})],
      series,
      cursor: {drag: {x: true, y: false}, points: {size: 5}},
      hooks: {draw: [(u) => {
        const y = u.valToPos(0, 'y', true);
        if (y < u.bbox.top || y > u.bbox.top + u.bbox.height) return;
        const g = u.ctx; g.save(); g.strokeStyle = '#9aa3b2'; g.setLineDash([4, 4]); g.lineWidth = devicePixelRatio;
        g.beginPath(); g.moveTo(u.bbox.left, y); g.lineTo(u.bbox.left + u.bbox.width, y); g.stroke(); g.restore();
      }]},
    }, [ts].concat(columns));
  }

  function renderVerdict() {
    const s = section('verdict', 'Verdict', 'Verdict');
    const V = analysis.verdict;
    if (!V || !V.class) { notComputed(s); return; }
    s.append(el('div', {class: 'verdict-class ' + V.class, id: 'verdict-class', text: V.class}));
    if (Array.isArray(V.evidence) && V.evidence.length)
      s.append(el('ul', {class: 'evidence'}, V.evidence.map((e) => el('li', {text: String(e)}))));
    else notComputed(s, 'evidence');
    if (V.rule) s.append(el('p', {class: 'rule', text: 'Rule: ' + V.rule}));
  }

  // --- resizing and start-up --------------------------------------------------------------------------
  let resizeTimer = null;
  window.addEventListener('resize', () => {
    clearTimeout(resizeTimer);
    resizeTimer = setTimeout(() => {
      report.charts.forEach((c) => c.fit());
    }, 100);
  });

  function guarded(name, fn) {
    // A bug in one section must not blank the page: say so in place, and let the test see it.
    try { fn(); } catch (err) {
      document.getElementById('main').append(el('p', {class: 'error', text: 'Could not draw ' + name + ': ' + err.message}));
      console.error(err);
    }
  }
  guarded('the header', renderHeader);
  guarded('the model', renderModel);
  guarded('the animation', renderAnimation);
  guarded('the time series', renderTimeSeries);
  guarded('the clearance joints', renderClearance);
  guarded('the statistics', renderStatistics);
  guarded('the Poincaré section', renderPoincare);
  guarded('the spectra', renderSpectra);
  guarded('the phase portraits', renderPhase);
  guarded('the Lyapunov exponent', renderLyapunov);
  guarded('the verdict', renderVerdict);
  document.getElementById('footer').textContent = 'Written by Lash. Data contract: docs/report-data.md (version ' +
    (D.version != null ? D.version : '?') + '). Self-contained: this file makes no network request. Plots by uPlot (MIT).';
  report.ready = true;
})();

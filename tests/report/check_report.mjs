// Browser test of a Lash report.html in Debian's headless Chromium (playwright-core, from
// report/node_modules): the page loads offline without errors, every chart and the animation draw.
//
//   node tests/report/check_report.mjs REPORT.html SCREENSHOT.png
//
// Fails (exit 1, one line per problem) when: the page asks for anything but its own file:// URL;
// a console error or an uncaught exception occurs; a uPlot chart has no coloured pixel in its plot
// area; the animation canvas is the same before and after 300 ms of play; a clearance inset is
// blank; the verdict (or "not computed" when there is none) is missing; the data has no
// channel_info or it lacks a channel the data mentions; a time-series legend entry, a channel
// picker tooltip or the statistics table shows a unit other than the one channel_info gives
// (display prefixes such as kN or 10³ m/s² allowed). LASH_REPORT_ALLOW_NO_CHANNEL_INFO=1 accepts
// data without channel_info (an older engine's) and then requires every unit to show as "–".
import {createRequire} from 'node:module';
import {mkdtempSync, rmSync, existsSync} from 'node:fs';
import {tmpdir} from 'node:os';
import path from 'node:path';
import {fileURLToPath, pathToFileURL} from 'node:url';

const here = path.dirname(fileURLToPath(import.meta.url));
const root = path.resolve(here, '..', '..');
const CHROMIUM = process.env.LASH_CHROMIUM || '/usr/bin/chromium';

function die(msg) {
  console.error(`check_report: ${msg}`);
  process.exit(1);
}

const [reportArg, shotArg] = process.argv.slice(2);
if (!reportArg || !shotArg) die('usage: node tests/report/check_report.mjs REPORT.html SCREENSHOT.png');
const reportPath = path.resolve(reportArg);
if (!existsSync(reportPath)) die(`no such file: ${reportPath}`);
if (!existsSync(CHROMIUM)) die(`${CHROMIUM} not found: install Debian's chromium (make deps)`);
let chromium;
try {
  chromium = createRequire(path.join(root, 'report', 'package.json'))('playwright-core').chromium;
} catch (err) {
  die('playwright-core is not installed in report/node_modules: run `make deps` (npm ci in report/)');
}

const failures = [];
const fail = (msg) => failures.push(msg);
const profile = mkdtempSync(path.join(tmpdir(), 'lash-report-chromium-'));
let context;
try {
  context = await chromium.launchPersistentContext(profile, {
    executablePath: CHROMIUM,
    headless: true,
    args: ['--headless', '--no-sandbox', '--disable-gpu', '--disable-background-networking',
           '--disable-component-update', '--no-first-run', '--disable-sync'],
    viewport: {width: 1280, height: 900},
    deviceScaleFactor: 1,
    offline: true,
    timeout: 20000,
  });
  const page = context.pages()[0] || await context.newPage();
  const url = pathToFileURL(reportPath).href;

  // No network: anything that is not this very file is aborted and fails the test.
  await context.route('**/*', (route) => {
    const u = route.request().url();
    if (u === url || u.split('#')[0] === url) return route.continue();
    fail(`the page requested ${u}`);
    return route.abort();
  });
  page.on('request', (req) => {
    const u = req.url();
    if (!u.startsWith('file:') && !u.startsWith('data:') && !u.startsWith('blob:')) fail(`network request: ${u}`);
  });
  page.on('console', (msg) => {
    if (msg.type() === 'error' || msg.type() === 'warning' && /Content Security Policy/.test(msg.text()))
      fail(`console ${msg.type()}: ${msg.text()}`);
  });
  page.on('pageerror', (err) => fail(`page error: ${err.message}`));

  await page.goto(url, {waitUntil: 'load', timeout: 15000});
  await page.waitForFunction(() => window.lashReport && window.lashReport.ready === true, null, {timeout: 10000})
    .catch(() => fail('the page never set window.lashReport.ready'));

  const data = await page.evaluate(() => JSON.parse(document.getElementById('lash-data').textContent));

  // Every uPlot chart: coloured (series) pixels inside the plot area; grid and axes are grey.
  const charts = await page.evaluate(() => window.lashReport.charts.map((c) => {
    const cv = c.u.ctx.canvas, b = c.u.bbox;
    const img = c.u.ctx.getImageData(b.left, b.top, Math.max(1, b.width), Math.max(1, b.height)).data;
    let coloured = 0;
    for (let i = 0; i < img.length; i += 4) {
      const r = img[i], g = img[i + 1], bl = img[i + 2], a = img[i + 3];
      if (a > 40 && Math.max(r, g, bl) - Math.min(r, g, bl) > 40) coloured++;
    }
    return {id: c.id, coloured, w: cv.width, h: cv.height, inDom: document.body.contains(cv)};
  }));
  if (!charts.length) fail('no uPlot chart on the page');
  for (const c of charts) {
    if (!c.inDom) fail(`chart ${c.id} is not in the page`);
    else if (c.coloured < 20) fail(`chart ${c.id} (${c.w}x${c.h}) draws no series (${c.coloured} coloured pixels)`);
  }
  const uplotCount = await page.evaluate(() => document.querySelectorAll('.uplot').length);
  if (uplotCount !== charts.length) fail(`${uplotCount} .uplot elements but ${charts.length} registered charts`);
  // The sections the data asks for have their charts.
  const ids = new Set(charts.map((c) => c.id));
  const A = data.analysis || {};
  const expect = [];
  for (const [name, J] of Object.entries(A.clearance || {})) {
    if (J && J.orbit && J.orbit.ex && J.orbit.ex.length) expect.push(`orbit-${name}`);
    if (J && ((J.histogram && J.histogram.counts && J.histogram.counts.length) ||
              (J.impact_velocities && J.impact_velocities.length))) expect.push(`hist-${name}`);
  }
  if (A.poincare && A.poincare.points && A.poincare.points.length) {
    expect.push('poincare');
    // One more chart per clearance joint whose section variables differ from the main ones.
    const main = JSON.stringify((A.poincare.variables || []).slice(0, 2));
    (Array.isArray(A.poincare.joints) ? A.poincare.joints : [])
      .filter((j) => j && Array.isArray(j.points) && j.points.length && Array.isArray(j.variables) &&
        j.variables.length === 2 && JSON.stringify(j.variables) !== main)
      .forEach((j, k) => expect.push('poincare-' + k));
  }
  if (A.spectra && Object.keys(A.spectra).length) expect.push('spectrum');
  if (A.lyapunov && A.lyapunov.history && A.lyapunov.history.length) expect.push('lyapunov');
  for (const id of expect) if (!ids.has(id)) fail(`no chart ${id} although the data has it`);
  if (![...ids].some((id) => id.startsWith('ts-'))) fail('no time-series chart');

  // Units and descriptions come from channel_info (docs/report-data.md), never from the names.
  const info = data.channel_info;
  const hasInfo = info !== null && typeof info === 'object' && !Array.isArray(info);
  const S = data.series || {};
  if (!hasInfo && process.env.LASH_REPORT_ALLOW_NO_CHANNEL_INFO !== '1')
    fail('the data has no channel_info (the unit and description of every channel, docs/report-data.md)');
  if (hasInfo) {
    const mentioned = new Set([
      ...Object.keys(S.channels || {}), ...Object.keys(S.ideal || {}),
      ...Object.keys(A.statistics || {}), ...Object.keys(A.comparison || {}), ...Object.keys(A.spectra || {}),
      ...(Array.isArray(A.phase) ? A.phase.flatMap((p) => (p ? [p.x, p.y] : [])) : []),
      ...((A.poincare && Array.isArray(A.poincare.variables)) ? A.poincare.variables : [])]);
    const lacking = [...mentioned].filter((n) => !(Object.hasOwn(info, n) && info[n] &&
      typeof info[n].unit === 'string' && typeof info[n].description === 'string'));
    if (lacking.length) fail(`channel_info lacks a unit and description for ${lacking.length} channel(s): ${lacking.slice(0, 6).join(', ')}`);
  }
  const unitOf = (n) => (hasInfo && Object.hasOwn(info, n) && info[n] && typeof info[n].unit === 'string' ? info[n].unit : '');
  const descOf = (n) => (hasInfo && Object.hasOwn(info, n) && info[n] && info[n].description ? String(info[n].description) : n);
  // A displayed unit: the unit itself, with an SI prefix (kN, mm) or a power of ten (10³ m/s²);
  // no unit shows as "–" or a bare power of ten.
  const POW10 = '10[⁻⁰¹²³⁴⁵⁶⁷⁸⁹]+';
  const showsUnit = (shown, unit) => (unit === ''
    ? shown === '–' || new RegExp(`^${POW10}$`).test(shown)
    : shown === unit || (shown.endsWith(' ' + unit) && new RegExp(`^${POW10} `).test(shown)) ||
      (shown.length === unit.length + 1 && shown.endsWith(unit) && 'nµmkMG'.includes(shown[0])));
  const legends = await page.evaluate(() => window.lashReport.charts.filter((c) => c.id.startsWith('ts-'))
    .flatMap((c) => c.u.series.slice(1).map((sr) => sr.label)));
  let withUnit = 0;
  for (const label of legends) {
    const m = /^(.+) \[(.*)\]$/.exec(label || '');
    if (!m) { if (!/ ideal$/.test(label || '')) fail(`time-series legend entry "${label}" has no [unit]`); continue; }
    const [, name, shown] = m;
    if (!showsUnit(shown, unitOf(name))) fail(`legend "${label}": channel_info gives ${name} the unit "${unitOf(name)}"`);
    if (unitOf(name)) withUnit++;
  }
  if (hasInfo && !withUnit) fail('no plotted time-series channel shows a unit from channel_info');
  const pickers = await page.evaluate(() => Array.from(document.querySelectorAll('label[data-channel]'))
    .map((l) => [l.dataset.channel, l.title]));
  if (pickers.length !== Object.keys(S.channels || {}).length)
    fail(`${pickers.length} channel checkboxes for ${Object.keys(S.channels || {}).length} channels`);
  for (const [name, title] of pickers) {
    const want = `${name}: ${descOf(name)} [${unitOf(name) || '–'}]`;
    if (!title.startsWith(want)) fail(`channel checkbox ${name}: tooltip "${title}", expected "${want}…"`);
  }
  const statRows = await page.evaluate(() => Array.from(document.querySelectorAll('#statistics tbody tr'))
    .map((tr) => Array.from(tr.children).map((td) => td.textContent)));
  for (const [name, desc, unit] of statRows) {
    if (unit !== (unitOf(name) || '–') || desc !== descOf(name))
      fail(`statistics row ${name}: "${desc}" [${unit}], channel_info gives "${descOf(name)}" [${unitOf(name) || '–'}]`);
  }
  if (!hasInfo && !(await page.locator('#timeseries').innerText()).includes('no channel_info'))
    fail('the data has no channel_info, yet the time-series section does not say so');

  // Hover over every chart: the cursor and legend code must not throw.
  for (const c of charts) {
    const over = page.locator(`#chart-${c.id} .u-over`);
    const box = await over.boundingBox().catch(() => null);
    if (!box) continue;
    await over.hover({position: {x: box.width * 0.4, y: box.height * 0.5}, force: true});
    await over.hover({position: {x: box.width * 0.6, y: box.height * 0.4}, force: true});
  }

  // The animation moves: compare the canvas before and after 300 ms of play.
  const frames = data.frames && data.frames.time ? data.frames.time.length : 0;
  if (frames > 1) {
    const snap = () => page.evaluate(() => window.lashReport.animation.canvas.toDataURL());
    const blank = await page.evaluate(() => {
      const c = window.lashReport.animation.canvas;
      const d = c.getContext('2d').getImageData(0, 0, c.width, c.height).data;
      let n = 0;
      for (let i = 3; i < d.length; i += 4) if (d[i] > 0) n++;
      return n;
    });
    if (blank < 500) fail(`the animation canvas is almost empty (${blank} drawn pixels)`);
    const before = await snap();
    await page.click('#anim-play');
    await page.waitForTimeout(300);
    await page.click('#anim-play');
    const after = await snap();
    const moved = await page.evaluate(() => window.lashReport.animation.frame());
    if (before === after) fail(`the animation canvas did not change in 300 ms of play (frame ${moved})`);
    // Scrub to the middle with the slider as a user would.
    await page.locator('#anim-slider').fill(String(Math.floor(frames / 2)));
  } else if (!(await page.locator('#animation .not-computed').count())) {
    fail('no animation frames, yet no "not computed" in the animation section');
  }

  // Each clearance inset is drawn (coloured journal dot and grey circle).
  const nInsets = Object.keys((data.frames && data.frames.clearance) || {}).length;
  const insets = await page.evaluate(() => window.lashReport.insets.map((c) => {
    const d = c.getContext('2d').getImageData(0, 0, c.width, c.height).data;
    let drawn = 0, coloured = 0;
    for (let i = 0; i < d.length; i += 4) {
      if (d[i + 3] > 40) drawn++;
      if (d[i + 3] > 40 && Math.max(d[i], d[i + 1], d[i + 2]) - Math.min(d[i], d[i + 1], d[i + 2]) > 40) coloured++;
    }
    return {joint: c.dataset.joint, drawn, coloured};
  }));
  if (insets.length !== nInsets) fail(`${insets.length} clearance insets for ${nInsets} clearance joints in frames`);
  for (const i of insets) if (i.drawn < 300 || i.coloured < 10) fail(`inset ${i.joint} is blank (${i.drawn} px)`);

  // The verdict, or an honest "not computed".
  const verdict = (await page.locator('#verdict').innerText().catch(() => '')).toLowerCase();
  const V = A.verdict;
  if (V && V.class) {
    if (!verdict.includes(String(V.class).toLowerCase())) fail(`verdict "${V.class}" is not shown`);
    for (const e of V.evidence || []) if (!verdict.includes(String(e).toLowerCase().slice(0, 20))) fail(`evidence "${e}" is not shown`);
  } else if (!verdict.includes('not computed')) fail('no verdict in the data, yet the page does not say "not computed"');

  // Sections the data leaves out say so instead of vanishing.
  for (const [key, id] of [['poincare', 'poincare'], ['spectra', 'spectra'], ['lyapunov', 'lyapunov'],
                           ['clearance', 'clearance'], ['comparison', 'comparison'], ['phase', 'phase']]) {
    const v = A[key];
    const empty = v == null || (typeof v === 'object' && Object.keys(v).length === 0);
    if (empty && !(await page.locator(`#${id} .not-computed`).count())) fail(`section ${id} is empty without "not computed"`);
  }
  const errors = await page.locator('main .error').allInnerTexts();
  for (const e of errors) fail(`the page reports: ${e}`);

  await page.evaluate(() => window.scrollTo(0, 0));
  await page.screenshot({path: path.resolve(shotArg), fullPage: true});
  console.log(`check_report: ${charts.length} charts, ${insets.length} insets, ${frames} frames; ` +
              `screenshot ${path.resolve(shotArg)}`);
} catch (err) {
  fail(`unexpected: ${err && err.stack ? err.stack : err}`);
} finally {
  if (context) await context.close().catch(() => {});
  rmSync(profile, {recursive: true, force: true});
}
if (failures.length) {
  for (const f of failures) console.error(`FAIL: ${f}`);
  console.error(`check_report: ${failures.length} problem(s) in ${reportPath}`);
  process.exit(1);
}
console.log('check_report: OK');

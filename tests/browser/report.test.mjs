// The browser test of report.html: opens the page of a compare run directory in a real
// headless Chromium (playwright-core driving /usr/bin/chromium; no browser download) and drives
// it like a user: keyboard switching, hovering a pixel and reading the readout, sorting the
// summary table, dragging a region. Values are checked against the EXR files through
// target/release/examples/exr_pixel. Takes screenshots into docs/figures/report-*.png.
//
//   node tests/browser/report.test.mjs RUN_DIR
//
// Environment: EXR_PIXEL (the exr_pixel binary), CHROMIUM (default /usr/bin/chromium),
// SCREENSHOTS (the folder for the PNGs, default docs/figures; `none` to skip them).
// Generates nothing itself: scripts/test-browser.sh makes the run and the report.

import { chromium } from 'playwright-core';
import { execFileSync } from 'node:child_process';
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import { pathToFileURL, fileURLToPath } from 'node:url';

const started = Date.now();
const here = path.dirname(fileURLToPath(import.meta.url));
const repo = path.resolve(here, '..', '..');
const runDir = process.argv[2] && path.resolve(process.argv[2]);
if (!runDir) {
  console.error('usage: node report.test.mjs RUN_DIR');
  process.exit(2);
}
const report = path.join(runDir, 'report.html');
const exrPixel = process.env.EXR_PIXEL || path.join(repo, 'target/release/examples/exr_pixel');
const executablePath = process.env.CHROMIUM || '/usr/bin/chromium';
const shots = process.env.SCREENSHOTS || path.join(repo, 'docs/figures');
for (const [f, what] of [[report, 'report.html (run `dibench report RUN_DIR`)'], [exrPixel, 'exr_pixel (cargo build --release --example exr_pixel)'], [executablePath, 'chromium (scripts/install-browser.sh)']]) {
  if (!fs.existsSync(f)) {
    console.error(`FAIL: ${f} is missing: ${what}`);
    process.exit(1);
  }
}

let failures = 0;
let checks = 0;
function check(ok, what) {
  checks++;
  if (ok) console.log(`ok   ${what}`);
  else { failures++; console.log(`FAIL ${what}`); }
}
const close = (a, b, rel) => Math.abs(a - b) <= rel * Math.max(Math.abs(a), Math.abs(b)) + 1e-30;
const exr = (...args) => execFileSync(exrPixel, args.map(String), { encoding: 'utf8' }).trim().split(/\s+/).map(Number);
// exr_pixel prints f32 values in their shortest form: Math.fround gives back the f32 itself.
const exrF32 = (...args) => exr(...args).map(Math.fround);

// The run's own view of itself, read here independently of the page.
function csv(file) {
  const [head, ...rows] = fs.readFileSync(file, 'utf8').trim().split('\n').map((l) => l.split(','));
  return rows.map((r) => Object.fromEntries(head.map((h, k) => [h, r[k]])));
}
const summary = csv(path.join(runDir, 'summary.csv'));
const results = csv(path.join(runDir, 'results.csv'));
const stemOf = (r) => (!r.sampler || r.sampler === 'independent' ? r.strategy : `${r.strategy}.${r.sampler}`);
const stems = [...new Set(summary.map(stemOf))];
const integrandOf = Object.fromEntries(summary.map((r) => [stemOf(r), r.integrand]));
const refDir = path.join(path.dirname(runDir), 'reference');
const refFile = (integrand) => {
  const manifest = JSON.parse(fs.readFileSync(path.join(refDir, `${integrand}.json`), 'utf8'));
  return path.join(refDir, manifest.files.image.name);
};

const userDataDir = fs.mkdtempSync(path.join(os.tmpdir(), 'dibench-chromium-'));
const context = await chromium.launchPersistentContext(userDataDir, {
  executablePath,
  headless: true,
  args: ['--headless', '--no-sandbox', '--disable-gpu', '--disable-background-networking', '--disable-component-update',
    '--disable-sync', '--disable-quic', '--no-first-run'],
  viewport: { width: 1400, height: 1000 },
  deviceScaleFactor: 1,
});
const pageErrors = [];
const requests = [];
try {
  const page = context.pages()[0] || await context.newPage();
  page.on('console', (m) => { if (m.type() === 'error') pageErrors.push(`console: ${m.text()}`); });
  page.on('pageerror', (e) => pageErrors.push(`pageerror: ${e.message}`));
  page.on('request', (r) => { if (!r.url().startsWith('file:') && !r.url().startsWith('data:')) requests.push(r.url()); });
  const t0 = Date.now();
  await page.goto(pathToFileURL(report).href);
  await page.waitForFunction(() => window.dibenchReport && window.dibenchReport.ready, null, { timeout: 30000 });
  console.log(`page ready in ${Date.now() - t0} ms (${(fs.statSync(report).size / 1048576).toFixed(2)} MiB)`);
  const R = (fn, ...a) => page.evaluate(fn, ...a);
  // Sticky elements (the navigation bar, the viewer's sidebar) would shift in element screenshots.
  await page.addStyleTag({ content: 'nav#toc, .sidebar { position: static !important; }' });

  // Every strategy's image and every reference decoded, with finite values.
  const names = await R(() => window.dibenchReport.images);
  const refNames = names.filter((n) => n.startsWith('reference'));
  check(refNames.length === new Set(Object.values(integrandOf)).size, `one reference per integrand: ${refNames.join(', ')}`);
  check(JSON.stringify(names.filter((n) => !n.startsWith('reference'))) === JSON.stringify(stems),
    `the strategies of summary.csv, in its order (${stems.length})`);
  const { width: W, height: H } = await R(() => ({ width: window.dibenchReport.width, height: window.dibenchReport.height }));
  for (const n of names) {
    const info = await R((n) => window.dibenchReport.info(n), n);
    check(info && info.values === 3 * W * H && info.finite === info.values && info.sum > 0, `${n}: ${W}×${H} RGB decoded, finite, not black`);
  }

  // Every image's values against the EXR, at a few pixels.
  const probes = [[0, 0], [W - 1, H - 1], [Math.floor(W / 2), Math.floor(H / 3)], [Math.floor(W / 5), Math.floor((4 * H) / 5)]];
  for (const stem of stems) {
    for (const [x, y] of probes) {
      const want = exrF32('pixel', path.join(runDir, `${stem}.exr`), x, y);
      const got = await R(([n, x, y]) => window.dibenchReport.pixel(n, x, y), [stem, x, y]);
      check(got.every((v, c) => v === want[c]), `${stem} (${x}, ${y}) = EXR ${want.join(' ')} exactly (page ${got.join(' ')})`);
    }
  }
  for (const r of refNames) {
    const integrand = r === 'reference' ? Object.values(integrandOf)[0] : r.slice('reference:'.length);
    const [x, y] = probes[2];
    const want = exrF32('pixel', refFile(integrand), x, y);
    const got = await R(([n, x, y]) => window.dibenchReport.pixel(n, x, y), [r, x, y]);
    check(got.every((v, c) => v === want[c]), `${r} (${x}, ${y}) = reference EXR exactly`);
  }

  // Keyboard: 1 and 2 select strategies 1 and 2, space toggles with the reference, arrows step.
  await page.keyboard.press('1');
  check(await R(() => window.dibenchReport.current()) === stems[0], `key 1 shows ${stems[0]}`);
  if (stems.length > 1) {
    await page.keyboard.press('2');
    check(await R(() => window.dibenchReport.current()) === stems[1], `key 2 shows ${stems[1]}`);
  }
  const before = await R(() => window.dibenchReport.current());
  await page.keyboard.press('Space');
  const ref = await R(() => window.dibenchReport.current());
  check(ref.startsWith('reference') && ref !== before, `space shows the reference (${ref})`);
  await page.keyboard.press('Space');
  check(await R(() => window.dibenchReport.current()) === before, 'space again goes back');
  await page.keyboard.press('ArrowRight');
  const after = await R(() => window.dibenchReport.current());
  check(after !== before && after === names[(names.indexOf(before) + 1) % names.length], `→ steps to ${after}`);
  check(await page.locator('#image-list li.current').getAttribute('data-name') === after, 'the list marks the current image');
  await page.keyboard.press('ArrowLeft');

  // Hover a known pixel: the readout shows its coordinates and the EXR's values.
  await page.keyboard.press('1');
  await page.keyboard.press('f');
  await page.locator('#view').scrollIntoViewIfNeeded();
  await page.waitForTimeout(50);
  // Zoom in with the wheel about the centre, so that a pixel is several screen pixels wide.
  const box = await page.locator('#view').boundingBox();
  await page.mouse.move(box.x + box.width / 2, box.y + box.height / 2);
  const s0 = (await R(() => window.dibenchReport.view())).scale;
  await page.mouse.wheel(0, -600);
  await page.waitForTimeout(100);
  const s1 = (await R(() => window.dibenchReport.view())).scale;
  check(s1 > s0 * 2, `the wheel zooms in (scale ${s0.toFixed(2)} → ${s1.toFixed(2)})`);
  const [hx, hy] = [Math.floor(W / 2) + 1, Math.floor(H / 2) - 2];
  const at = await R(([x, y]) => window.dibenchReport.screenOf(x, y), [hx, hy]);
  await page.mouse.move(at.x, at.y);
  await page.waitForTimeout(50);
  const text = await page.locator('#readout').innerText();
  const m = text.match(/x (\d+) y (\d+)/);
  const v = text.match(/: R (\S+) G (\S+) B (\S+)/);
  const want = exr('pixel', path.join(runDir, `${stems[0]}.exr`), hx, hy);
  check(m && Number(m[1]) === hx && Number(m[2]) === hy, `readout at (${hx}, ${hy}): "${text.split('\n')[0]}"`);
  check(v && [1, 2, 3].every((k) => close(Number(v[k]), want[k - 1], 1e-6)),
    `readout values = EXR ${want.join(' ')} to 7 digits`);
  // Drag pans: the pixel under the mouse moves with it.
  const t1 = await R(() => window.dibenchReport.view());
  await page.mouse.down();
  await page.mouse.move(at.x + 40, at.y + 25, { steps: 4 });
  await page.mouse.up();
  const t2 = await R(() => window.dibenchReport.view());
  check(Math.abs(t2.tx - t1.tx - 40) < 1 && Math.abs(t2.ty - t1.ty - 25) < 1, 'dragging pans by the mouse movement');
  // Down to single pixels: the grid shows and the readout follows.
  await page.mouse.wheel(0, -900);
  await page.waitForTimeout(100);
  const s2 = (await R(() => window.dibenchReport.view())).scale;
  check(s2 >= 24, `zoomed to ${s2.toFixed(1)} screen pixels per image pixel`);
  if (shots !== 'none') {
    fs.mkdirSync(shots, { recursive: true });
    const c = await R(([x, y]) => window.dibenchReport.screenOf(x, y), [hx, hy]);
    await page.mouse.move(c.x, c.y);
    await page.waitForTimeout(50);
    await page.locator('#viewer .stage').screenshot({ path: path.join(shots, 'report-zoom.png') });
  }

  // Exposure: the slider changes the displayed pixels, not the values.
  await page.locator('#exposure').fill('2');
  check(await R(() => window.dibenchReport.exposure()) === 2, 'the exposure slider sets +2 stops');

  // Region by shift+drag, against RMSE/relMSE computed from the EXRs by dibench::metrics.
  await page.keyboard.press('f');
  await page.waitForTimeout(50);
  const [x0, y0, x1, y1] = [Math.floor(W / 8), Math.floor(H / 6), Math.floor(W / 2), Math.floor((2 * H) / 3)];
  const a = await R(([x, y]) => window.dibenchReport.screenOf(x, y), [x0, y0]);
  const b = await R(([x, y]) => window.dibenchReport.screenOf(x, y), [x1 - 1, y1 - 1]);
  await page.mouse.move(a.x, a.y);
  await page.keyboard.down('Shift');
  await page.mouse.down();
  await page.mouse.move((a.x + b.x) / 2, (a.y + b.y) / 2, { steps: 3 });
  await page.mouse.move(b.x, b.y, { steps: 3 });
  await page.mouse.up();
  await page.keyboard.up('Shift');
  const region = await R(() => window.dibenchReport.region());
  check(region && region.x0 === x0 && region.y0 === y0 && region.x1 === x1 && region.y1 === y1,
    `shift+drag selects [${x0}, ${x1}) × [${y0}, ${y1}): ${JSON.stringify(region)}`);
  const hook = await R((r) => window.dibenchReport.regionStats(r[0], r[1], r[2], r[3]), [x0, y0, x1, y1]);
  for (const stem of stems) {
    const [rmse, relmse] = exr('region', path.join(runDir, `${stem}.exr`), refFile(integrandOf[stem]), x0, y0, x1, y1);
    const row = page.locator(`#region-table tbody tr[data-name="${stem}"]`);
    const shownRmse = Number(await row.getAttribute('data-rmse'));
    const shownRel = Number(await row.getAttribute('data-relmse'));
    check(close(shownRmse, rmse, 1e-9) && close(shownRel, relmse, 1e-9),
      `${stem}: region RMSE ${shownRmse.toExponential(6)} relMSE ${shownRel.toExponential(6)} = exr_pixel's ${rmse.toExponential(6)} ${relmse.toExponential(6)}`);
    check(close(hook[stem].rmse, rmse, 1e-9), `${stem}: the hook's regionStats agrees`);
    const cell = Number((await row.locator('td').nth(2).innerText()));
    check(close(cell, rmse, 1e-3), `${stem}: the table shows ${cell}`);
  }
  // The whole image's RMSE of run 0's image is results.csv's final run-0 value (which was
  // computed before the image was rounded to f32 for its EXR).
  const whole = await R(() => window.dibenchReport.wholeStats());
  for (const stem of stems) {
    const last = results.filter((r) => stemOf(r) === stem && r.run === '0').sort((p, q) => Number(p.checkpoint) - Number(q.checkpoint)).pop();
    check(close(whole[stem].rmse, Number(last.rmse), 1e-4), `${stem}: whole-image RMSE ${whole[stem].rmse.toExponential(5)} = results.csv ${last.rmse}`);
  }
  await page.keyboard.press('1');
  const fullView = await page.locator('#viewer').boundingBox();
  if (shots !== 'none') {
    await page.mouse.move(b.x - 30, b.y - 20);
    await page.locator('#viewer').screenshot({ path: path.join(shots, 'report-viewer.png') });
  }

  // Sorting: by rmse_mean ascending, then descending; by strategy (text).
  const th = page.locator('#summary-table th[data-col="rmse_mean"]');
  const column = async (c) => page.locator(`#summary-table tbody td[data-col="${c}"]`).evaluateAll((tds) => tds.map((t) => t.dataset.value));
  await th.click();
  const up = (await column('rmse_mean')).map(Number);
  check(up.every((x, k) => k === 0 || up[k - 1] <= x), `sorted by rmse_mean ascending: ${up.map((x) => x.toExponential(2)).join(' ')}`);
  check(await th.getAttribute('aria-sort') === 'ascending', 'the header says ascending');
  await th.click();
  const down = (await column('rmse_mean')).map(Number);
  check(down.every((x, k) => k === 0 || down[k - 1] >= x), 'a second click sorts descending');
  const sth = page.locator('#summary-table th[data-col="strategy"]');
  await sth.click();
  const names2 = await column('strategy');
  check(names2.every((x, k) => k === 0 || names2[k - 1].localeCompare(x, undefined, { numeric: true }) <= 0), `sorted by strategy: ${names2.join(' ')}`);
  const verdicts = await page.locator('#summary-table td.verdict').count();
  check(verdicts === summary.length, 'every row has a styled vs_best verdict');
  await th.click();
  if (shots !== 'none') {
    // Wide enough for the main columns without scrolling.
    await page.setViewportSize({ width: 1800, height: 1000 });
    await page.locator('#summary .table-wrap').screenshot({ path: path.join(shots, 'report-table.png') });
    await page.setViewportSize({ width: 1400, height: 1000 });
    await page.locator('#convergence').screenshot({ path: path.join(shots, 'report-convergence.png') });
  }
  const lines = await page.locator('#plot svg .series').count();
  check(lines === stems.length, `the convergence plot has one line per strategy (${lines})`);

  // Error maps: relMSE mode by key, the legend, one map per strategy and kind or a "no" cell.
  await page.locator('#viewer').scrollIntoViewIfNeeded();
  await page.keyboard.press('e');
  check(await R(() => window.dibenchReport.mode()) === 'relmse', 'key e shows the relMSE map');
  check(await page.locator('#legend .colourbar').count() === 1, 'with a colour bar');
  // FLIP: a strategy with <stem>.flip.exr (compare writes one per strategy) shows it, with
  // the EXR's values; one without says so.
  const withFlip = stems.filter((s) => fs.existsSync(path.join(runDir, `${s}.flip.exr`)));
  const withoutFlip = stems.filter((s) => !withFlip.includes(s));
  await page.keyboard.press('p');
  if (withoutFlip.length) {
    await R((n) => window.dibenchReport.select(n), withoutFlip[0]);
    const msg = await page.locator('#view-message').innerText();
    check(msg.includes('no FLIP map'), `FLIP mode without a map: "${msg}"`);
  }
  for (const stem of withFlip) {
    await R((n) => window.dibenchReport.select(n), stem);
    const msg = await page.locator('#view-message').innerText();
    check(msg === '' && await page.locator('#legend .colourbar').count() === 1, `FLIP mode shows ${stem}.flip.exr with its colour bar`);
    const [x, y] = probes[2];
    const [f] = exrF32('pixel', path.join(runDir, `${stem}.flip.exr`), x, y);
    const got = await R(([n, x, y]) => window.dibenchReport.mapValue(n, 'flip', x, y), [stem, x, y]);
    check(got === f && f >= 0 && f <= 1, `${stem}: FLIP map at (${x}, ${y}) = the EXR's ${f} (page: ${got})`);
  }
  await page.keyboard.press('1');
  await page.keyboard.press('e');
  const cells = await page.locator('#errormap-grid [data-mode]').count();
  check(cells === 3 * stems.length, `error map grid: ${cells} cells for ${stems.length} strategies`);
  const [px, py] = probes[2];
  const relmseAt = await R(([n, x, y]) => window.dibenchReport.mapValue(n, 'relmse', x, y), [stems[0], px, py]);
  const [ir, ig, ib] = exrF32('pixel', path.join(runDir, `${stems[0]}.exr`), px, py);
  const [rr, rg, rb] = exrF32('pixel', refFile(integrandOf[stems[0]]), px, py);
  const expect = ([[ir, rr], [ig, rg], [ib, rb]].reduce((s, [i, r]) => s + ((i - r) ** 2) / (r * r + 0.01), 0)) / 3;
  check(close(relmseAt, expect, 1e-6), `relMSE map at (${px}, ${py}) = ${expect.toExponential(5)}`);
  if (shots !== 'none') {
    await page.locator('#viewer').screenshot({ path: path.join(shots, 'report-relmse.png') });
    await page.locator('#errormaps').screenshot({ path: path.join(shots, 'report-errormaps.png') });
  }
  check(fullView.height > 300, 'the viewer has a usable size');
} finally {
  await context.close();
  fs.rmSync(userDataDir, { recursive: true, force: true });
}
check(pageErrors.length === 0, `no console errors or page errors${pageErrors.length ? ': ' + pageErrors.join('; ') : ''}`);
check(requests.length === 0, `no network requests${requests.length ? ': ' + requests.join(', ') : ''}`);
console.log(`${checks - failures}/${checks} checks passed in ${((Date.now() - started) / 1000).toFixed(1)} s`);
process.exit(failures ? 1 : 0);

// SPDX-License-Identifier: MIT
// The page of `harap view` in headless Chromium (Debian's /usr/bin/chromium driven by
// puppeteer-core; nothing downloads a browser). Starts the server itself on a free port.
//
//   node web/test/browser_test.mjs HARAP_EXECUTABLE SCENARIO.toml [--screenshot FILE]
//        [--benchmark DRAGS] [--tolerance T] [--display-vertices N] [--page-display N|all]
// (--display-vertices is the server's budget; a page drawn by a software renderer, as here, asks
// for at most 20000 vertices unless --page-display says otherwise.)
//
// The test: the page loads and solves; a handle dragged with synthesized mouse events moves the
// mesh through preview frames and a full solve on release; the energy the page shows equals
// `harap deform`'s on the scenario the page exports; a handle is added and removed; malformed
// messages are refused with errors while the page keeps working; the screenshot is not blank;
// the hierarchy level slider colours the coarsest level's clusters.
// --benchmark N: N drags and five added and removed handles, then the page's own timers as JSON
// (docs/results.md); then three drags each started right after a release (`regrab`: the first
// preview drawn while the release's full solve runs, `regrab_ms`; full solves stopped by them,
// `full_solves_stopped`).
// Exits 77 (ctest: skipped) when Chromium is absent.
import { spawn, spawnSync } from 'node:child_process';
import http from 'node:http';
import { existsSync, mkdtempSync, readFileSync, writeFileSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import puppeteer from 'puppeteer-core';

const chromium = process.env.HARAP_CHROMIUM ?? '/usr/bin/chromium';
const [harap, scenario, ...rest] = process.argv.slice(2);
const option = (name, fallback) => {
  const i = rest.indexOf(name);
  return i >= 0 ? rest[i + 1] : fallback;
};
const screenshotFile = option('--screenshot', null);
const benchmarkDrags = Number(option('--benchmark', '0'));
const tolerance = option('--tolerance', '1e-8');
const displayVertices = option('--display-vertices', null);
const pageDisplay = option('--page-display', null);
if (!existsSync(chromium)) {
  console.log(`skipped: no Chromium at ${chromium} (Debian: apt-get install chromium; ` +
    '.ci/setup installs it)');
  process.exit(77);
}

let failures = 0, passes = 0;
function check(condition, what) {
  if (condition) {
    passes += 1;
    console.log(`ok: ${what}`);
  } else {
    failures += 1;
    console.log(`FAILED: ${what}`);
  }
}

const server = spawn(harap, ['view', scenario, '--port', '0', '--tolerance', tolerance,
  '--threads', '2', ...(displayVertices ? ['--display-vertices', displayVertices] : [])], { stdio: ['ignore', 'pipe', 'inherit'] });
const url = await new Promise((resolve, reject) => {
  let output = '';
  server.stdout.on('data', (chunk) => {
    output += chunk;
    const match = output.match(/http:\/\/127\.0\.0\.1:\d+\//);
    if (match) resolve(match[0]);
  });
  server.on('exit', (code) => reject(new Error(`harap view exited with ${code}: ${output}`)));
});
const browser = await puppeteer.launch({
  executablePath: chromium, headless: true,
  args: ['--no-sandbox', '--use-angle=swiftshader', '--enable-unsafe-swiftshader',
    '--window-size=1000,700'],
  defaultViewport: { width: 1000, height: 700 },
});
const page = await browser.newPage();
page.on('pageerror', (error) => check(false, `no page error (${error.message})`));
const waitFor = (fn, arg, timeout = 60000) =>
  page.waitForFunction(fn, { timeout, polling: 20 }, arg);

try {
  await page.goto(pageDisplay === null ? url : `${url}?display=${pageDisplay}`);
  await waitFor(() => window.harapView.ready && window.harapView.lastSolve?.mode === 'full',
    undefined, 120000);
  const first = await page.evaluate(() => ({ energy: window.harapView.energy,
    positions: window.harapView.positions(), groups: window.harapView.groups.length }));
  check(first.groups >= 1 && Number.isFinite(first.energy), 'the page loads and solves');

  // The page's first solve starts from the rest pose, as `harap deform` does: on the scenario the
  // page exports, both solve one problem from one start and end at the same energy.
  const dir = mkdtempSync(join(tmpdir(), 'harap-view-test-'));
  async function exportAndDeform() {
    await page.evaluate(() => { window.harapView.scenarioToml = null; window.harapView.requestScenario(); });
    await waitFor(() => window.harapView.scenarioToml !== null);
    writeFileSync(join(dir, 'scenario.toml'), await page.evaluate(() => window.harapView.scenarioToml));
    const optimizer = await page.evaluate(() => window.harapView.session.optimizer);
    const deform = spawnSync(harap, ['deform', join(dir, 'scenario.toml'), '--tolerance', tolerance,
      '--optimizer', optimizer, '--report', join(dir, 'report.json'), '--threads', '2', '-q'],
    { encoding: 'utf8' });
    return { status: deform.status, stderr: deform.stderr ?? '', energy: deform.status === 0
      ? JSON.parse(readFileSync(join(dir, 'report.json'), 'utf8')).energy : null };
  }
  const fromRest = await exportAndDeform();
  const shown = await page.evaluate(() => document.getElementById('energy').textContent);
  const relative = Math.abs(first.energy - fromRest.energy) / Math.abs(fromRest.energy);
  check(fromRest.status === 0 && relative < 1e-6 &&
    Math.abs(Number(shown) - first.energy) <= 1e-9 * first.energy,
  `energy shown ${shown} equals harap deform's ${fromRest.energy} on the exported scenario ` +
    `(relative ${relative.toExponential(2)}) ${fromRest.stderr}`);

  // Drag the last handle's gizmo centre across the screen.
  // `waitForFull`: wait for the release's own full solve to be drawn.
  async function drag(dx, dy, steps, waitForFull = true) {
    const framesBefore = await page.evaluate(() => window.harapView.framesDrawn);
    const start = await page.evaluate(() => window.harapView.gizmoScreenPosition());
    await page.mouse.move(start.x, start.y);
    await page.mouse.down();
    for (let i = 1; i <= steps; ++i) {
      await page.mouse.move(start.x + (dx * i) / steps, start.y + (dy * i) / steps);
      await new Promise((resolve) => setTimeout(resolve, 16));
    }
    await page.mouse.up();
    const release = await page.evaluate(() => window.harapView.releaseId);
    if (waitForFull) {
      await waitFor((id) => window.harapView.lastSolve?.id === id &&
        window.harapView.lastSolve.mode === 'full', release);
    }
    return framesBefore;
  }
  const framesBefore = await drag(120, -60, 12);
  const after = await page.evaluate(() => ({ energy: window.harapView.energy,
    positions: window.harapView.positions(), frames: window.harapView.framesDrawn,
    previews: window.harapView.timings.preview.length }));
  let moved = 0;
  for (let i = 0; i < after.positions.length; ++i)
    moved = Math.max(moved, Math.abs(after.positions[i] - first.positions[i]));
  check(moved > 1e-3, `dragging the gizmo moved the mesh (by up to ${moved.toFixed(4)})`);
  check(after.previews >= 1 && after.frames > framesBefore + 1,
    `preview frames streamed while dragging (${after.previews}) and a full solve followed`);
  // Each preview's time is its three parts: queued, answered (which contains the server's
  // solve), drawn; one entry of each per preview.
  const parts = await page.evaluate(() => {
    const t = window.harapView.timings;
    return {
      lengths: [t.preview, t.previewQueued, t.previewAnswered, t.previewDrawn, t.previewSolve]
        .map((values) => values.length),
      rest: t.preview.map((total, i) =>
        total - t.previewQueued[i] - t.previewAnswered[i] - t.previewDrawn[i]),
      negative: [t.previewQueued, t.previewAnswered, t.previewDrawn].flat().filter((v) => v < 0)
        .length,
      answeredBeforeSolve: t.previewAnswered.filter((v, i) => v + 1 < t.previewSolve[i]).length,
    };
  });
  const worst = Math.max(0, ...parts.rest.map(Math.abs));
  check(parts.lengths.every((n) => n === after.previews) && worst < 1e-6 && parts.negative === 0 &&
    parts.answeredBeforeSolve === 0,
    `each preview's time is queued + answered + drawn, none negative, each answer no sooner than ` +
    `the server's solve (entries ${parts.lengths.join(', ')} for ${after.previews} previews; ` +
    `largest difference ${worst.toFixed(6)} ms; ${parts.negative} negative; ` +
    `${parts.answeredBeforeSolve} answered before the solve)`);
  // Without a GPU: the display the page asks for, and half resolution only while dragging.
  const drawing = await page.evaluate(() => ({ software: window.harapView.softwareRenderer,
    requested: window.harapView.displayRequested, low: window.harapView.lowResolutionFrames,
    ratio: window.harapView.pixelRatio(), device: window.devicePixelRatio }));
  if (drawing.software) {
    check(pageDisplay !== null || drawing.requested === 20000,
      `a software renderer asks for a display of 20000 vertices (${drawing.requested})`);
    check(drawing.low >= 1 && drawing.ratio === drawing.device,
      `a software renderer drew ${drawing.low} frames at half resolution while dragging and ` +
      `is back at ${drawing.ratio}`);
  }

  // The scenario exported after the drag: the targets as a rigid motion per handle (the server
  // refuses to write targets that are not one), a problem `harap deform` solves. Its energy is
  // not the page's: the session started from the previous frame, `harap deform` from the rest
  // pose, and on a real mesh the two runs stop at energies apart by more than the tolerance.
  const dragged = await exportAndDeform();
  const draggedRelative = Math.abs(after.energy - dragged.energy) / Math.abs(dragged.energy);
  // Only gross differences (targets the page did not solve for) are caught here.
  check(dragged.status === 0 && draggedRelative < 0.05, 'harap deform on the scenario exported ' +
    `after the drag ends near the page's energy: ${dragged.energy} against ${after.energy} ` +
    `(relative ${draggedRelative.toExponential(2)}) ${dragged.stderr}`);

  // Add a handle at a vertex halfway up, then remove it.
  const editsBefore = await page.evaluate(() => window.harapView.timings.edit.length);
  await page.evaluate(() => {
    const rest = window.harapView.positions();
    let best = 0;
    for (let v = 0; v < rest.length / 3; ++v)
      if (Math.abs(rest[3 * v + 2] - 0.5) < Math.abs(rest[3 * best + 2] - 0.5)) best = v;
    window.harapView.addHandle(best);
  });
  await waitFor((n) => window.harapView.groups.length === n + 1, first.groups);
  await page.evaluate((g) => window.harapView.removeHandle(g), first.groups);
  await waitFor((n) => window.harapView.groups.length === n, first.groups);
  check(true, 'a handle was added and removed');
  await waitFor((n) => window.harapView.timings.edit.length === n + 2, editsBefore);
  check(await page.evaluate((n) => window.harapView.timings.edit.length === n + 2, editsBefore),
    'the page timed both handle edits');

  // Malformed messages: each answered with an error; the session still solves.
  const errorsBefore = await page.evaluate(() => window.harapView.errors.length);
  await page.evaluate(() => {
    const send = window.harapView.sendRaw;
    send('not json');
    send(JSON.stringify({ type: 'move', group: 99, transform: [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0] }));
    send(JSON.stringify({ type: 'move', group: 0, transform: [2, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0] }));
    send(JSON.stringify({ type: 'add_handle', vertex: -1, radius: 0.1 }));
    send('{"type":"add_handle","vertex":0,"radius":NaN}');
    send(new Uint8Array([1, 2, 3, 4]));
  });
  await waitFor((n) => window.harapView.errors.length >= n + 6, errorsBefore);
  const errors = await page.evaluate((n) => window.harapView.errors.slice(n).map((e) => e.message),
    errorsBefore);
  check(errors.length === 6, `malformed messages refused: ${errors.join(' | ')}`);
  const solvesBefore = await page.evaluate(() => window.harapView.timings.full.length);
  await page.evaluate(() => window.harapView.sendRaw(JSON.stringify({ type: 'solve', id: 100000 })));
  await waitFor(() => window.harapView.lastSolve?.id === 100000);
  check(solvesBefore >= 1, 'the session still solves after them');

  // The picture: not blank (mesh pixels differ from the background).
  const coloured = await page.evaluate(async () => {
    const canvas = document.querySelector('#viewport canvas');
    const image = new Image();
    image.src = canvas.toDataURL('image/png');
    await image.decode();
    const scratch = document.createElement('canvas');
    scratch.width = image.width;
    scratch.height = image.height;
    const context = scratch.getContext('2d');
    context.drawImage(image, 0, 0);
    const pixels = context.getImageData(0, 0, image.width, image.height).data;
    let differing = 0;
    for (let i = 0; i < pixels.length; i += 4) {
      if (Math.abs(pixels[i] - 244) + Math.abs(pixels[i + 1] - 244) + Math.abs(pixels[i + 2] - 242) > 30)
        differing += 1;
    }
    return differing / (pixels.length / 4);
  });
  check(coloured > 0.02, `the screenshot is not blank (${(100 * coloured).toFixed(1)}% mesh pixels)`);
  if (screenshotFile) await page.screenshot({ path: screenshotFile });

  // The hierarchy level slider: the coarsest level's clusters, fewer than the vertices drawn.
  const levels = await page.evaluate(() => window.harapView.session.levels);
  await page.evaluate((l) => window.harapView.setLevel(l), levels - 1);
  await waitFor((l) => window.harapView.levelShown === l, levels - 1);
  const clusters = await page.evaluate(() => window.harapView.clusterCount());
  const drawn = await page.evaluate(() => window.harapView.mesh.display_vertices);
  check(levels > 1 && clusters > 1 && clusters < drawn / 2,
    `level ${levels - 1} of ${levels} shows ${clusters} clusters of ${drawn} vertices`);
  await page.evaluate(() => window.harapView.setLevel(0));

  // The display a page asks for in its address: fewer vertices drawn, every one solved; a bad
  // count is named on the page and the default applies.
  for (const asked of ['150', 'abc']) {
    const other = await browser.newPage();
    other.on('pageerror', (error) => check(false, `no page error (${error.message})`));
    await other.goto(`${url}?display=${asked}`);
    await other.waitForFunction(() => window.harapView.ready, { timeout: 60000, polling: 20 });
    const seen = await other.evaluate(() => ({ mesh: window.harapView.mesh,
      errors: document.getElementById('errors').textContent }));
    if (asked === '150') {
      check(seen.mesh.display_vertices <= 150 && seen.mesh.display_vertices > 30 &&
        seen.mesh.vertices > 150, `?display=150 draws ${seen.mesh.display_vertices} of ` +
        `${seen.mesh.vertices} vertices`);
    } else {
      check(seen.errors.includes('display=abc is neither') && seen.mesh.display_vertices > 150,
        `?display=abc is named on the page (${seen.errors}) and the default applies`);
    }
    await other.close();
  }
  // A WebSocket address with a bad query is refused before the upgrade, naming the problem.
  const refusal = await new Promise((resolve) => {
    const request = http.request(`${url}ws?display_vertices=abc`, { headers: {
      Connection: 'Upgrade', Upgrade: 'websocket', 'Sec-WebSocket-Version': '13',
      'Sec-WebSocket-Key': 'dGhlIHNhbXBsZSBub25jZQ==' } });
    request.on('response', (response) => {
      let body = '';
      response.on('data', (chunk) => { body += chunk; });
      response.on('end', () => resolve({ status: response.statusCode, body }));
    });
    request.on('upgrade', (response, socket) => { socket.destroy(); resolve({ status: 101 }); });
    request.on('error', (error) => resolve({ status: 0, body: error.message }));
    request.end();
  });
  check(refusal.status === 400 && refusal.body.includes("display_vertices = 'abc' is not an integer"),
    `a WebSocket address with a bad query is refused (${refusal.status}: ${refusal.body?.trim()})`);

  if (benchmarkDrags > 0) {
    await page.evaluate(() => {
      const timings = window.harapView.timings;
      for (const key of Object.keys(timings)) timings[key] = [];
    });
    for (let d = 0; d < benchmarkDrags; ++d) await drag(d % 2 ? -80 : 80, d % 2 ? 40 : -40, 20);
    const edits = 5;  // each an added and a removed handle
    let removal;
    for (let e = 0; e < edits; ++e) {
      const n = await page.evaluate(() => window.harapView.groups.length);
      await page.evaluate(() => window.harapView.addHandle(0));
      await waitFor((m) => window.harapView.groups.length === m + 1, n);
      removal = await page.evaluate((g) => window.harapView.removeHandle(g), n);
      await waitFor((m) => window.harapView.groups.length === m, n);
    }
    // The last removal's colours may be drawn after its groups arrived, and its full solve
    // after them.
    await waitFor((n) => window.harapView.timings.edit.length === n, 2 * edits);
    await waitFor((id) => window.harapView.lastSolve?.id === id, removal);
    const timings = await page.evaluate(() => window.harapView.timings);
    // Drags started right after a release, while its full solve runs: the first preview drawn,
    // and how many full solves a newer request stopped.
    timings.regrab = [];
    const stoppedBefore = await page.evaluate(() => window.harapView.stoppedSolves);
    for (let d = 0; d < 3; ++d) {
      await drag(d % 2 ? -40 : 40, 20, 6, /*waitForFull=*/false);
      await waitFor(() => !window.harapView.previewBusy());
      const previews = await page.evaluate(() => window.harapView.timings.preview.length);
      await drag(d % 2 ? 40 : -40, -20, 6);
      timings.regrab.push(await page.evaluate((n) => window.harapView.timings.preview[n], previews));
    }
    const stopped = await page.evaluate((n) => window.harapView.stoppedSolves - n, stoppedBefore);
    const median = (values) => {
      const sorted = [...values].sort((a, b) => a - b);
      return sorted.length ? sorted[Math.floor(sorted.length / 2)] : null;
    };
    // The three figures, and where a preview's time goes: queued behind the one in flight,
    // answered (the server's solve, alone in previewSolve, and the page's handling of the
    // positions frame, normals included, in frame), drawn (one render, in render, and the wait
    // for the frame on the screen).
    const summary = { scenario, drags: benchmarkDrags };
    for (const [key, values] of Object.entries(timings))
      summary[`${key}_ms`] = { median: median(values), count: values.length };
    summary.regrab_ms.values = timings.regrab;
    summary.full_solves_stopped = stopped;
    console.log(JSON.stringify(summary));
  }
} catch (error) {
  check(false, `no exception (${error.stack})`);
} finally {
  await browser.close();
  server.kill('SIGTERM');
}
console.log(`${passes} passed, ${failures} failed`);
process.exit(failures ? 1 : 0);

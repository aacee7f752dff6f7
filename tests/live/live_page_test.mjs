// The sinew-live page in a real browser (Debian's chromium, headless, driven by puppeteer-core):
// open the page, receive frames, move the muscle slider and see the skin contract in the streamed
// positions, click-drag on the skin and see the picked region move, pause and resume, record, then
// check that sinew-render reads the recording and that sinew-simulate on the reproducing scene
// gives the same bits; take a screenshot that is not blank and shows the colour bar; play the
// recording back (sinew-live --play), scrub to its last frame and colour it by von Mises stress.
//
// Environment: SINEW_LIVE, SINEW_SIMULATE, SINEW_RENDER, LIVE_TEST_MODEL, LIVE_COMPARE (programs),
// NODE_MODULES (where puppeteer-core is), CHROMIUM (the browser), WORK (a scratch folder),
// SCREENSHOT (optional: where to copy the screenshot). Exit 77 (ctest: skipped) when chromium or
// puppeteer-core is missing.
import { spawn, spawnSync } from 'node:child_process';
import fs from 'node:fs';
import path from 'node:path';
import { createRequire } from 'node:module';

const env = process.env;
const fail = (msg) => { console.error(`FAIL: ${msg}`); process.exitCode = 1; throw new Error(msg); };
const check = (ok, msg) => { if (!ok) fail(msg); console.log(`ok: ${msg}`); };
const sleep = (ms) => new Promise((r) => setTimeout(r, ms));

if (!fs.existsSync(env.CHROMIUM || '')) {
  console.log(`SKIP: no chromium at '${env.CHROMIUM}' (scripts/install-deps installs it)`);
  process.exit(77);
}
let puppeteer;
try {
  puppeteer = createRequire(path.join(env.NODE_MODULES, 'x.js'))('puppeteer-core');
} catch {
  console.log(`SKIP: no puppeteer-core under ${env.NODE_MODULES} (scripts/install-deps installs it)`);
  process.exit(77);
}

const work = env.WORK;
fs.rmSync(work, { recursive: true, force: true });
fs.mkdirSync(work, { recursive: true });
const run = (cmd, args) => {
  const r = spawnSync(cmd, args, { cwd: work, encoding: 'utf8' });
  if (r.status !== 0) fail(`${path.basename(cmd)} ${args.join(' ')}: ${r.stdout}${r.stderr}`);
  return r.stdout;
};
run(env.LIVE_TEST_MODEL, [work]);
// The test scene lasts 2 s, 20 s of wall time at --speed 0.1: a slow or loaded machine (browser
// start, swiftshader) reached its end, paused there, before the drag (seen in CI). A minute of
// scene keeps the engine running through every step below.
{
  const scene = path.join(work, 'live_box.yaml'), text = fs.readFileSync(scene, 'utf8');
  if (!/^duration: 2\.0$/m.test(text)) fail(`live_box.yaml has no 'duration: 2.0' line:\n${text}`);
  fs.writeFileSync(scene, text.replace(/^duration: 2\.0$/m, 'duration: 60.0'));
}

// With an access token (as any non-loopback bind has): the page, its scripts and three.js load by
// the URL's ?token= and the cookie the server sets.
const server = spawn(env.SINEW_LIVE, ['live_box.yaml', '--device', 'cpu', '--threads', '1',
                                      '--port', '0', '--frame-rate', '20', '--speed', '0.1',
                                      '--token', 'page-test-token-2026'], { cwd: work });
let out = '';
server.stdout.on('data', (d) => { out += d; });
server.stderr.on('data', (d) => { out += d; });
let browser, player;
try {
  for (let k = 0; k < 300 && !/open (http\S+)/.test(out); ++k) await sleep(50);
  const url = (out.match(/open (http\S+)/) || [])[1];
  check(url && url.endsWith('?token=page-test-token-2026'), `sinew-live printed its URL (${url})`);

  browser = await puppeteer.launch({
    executablePath: env.CHROMIUM, headless: true,
    args: ['--no-sandbox', '--use-angle=swiftshader', '--enable-unsafe-swiftshader',
           '--window-size=1100,700'] });
  const page = await browser.newPage();
  await page.setViewport({ width: 1100, height: 700 });
  const errors = [];
  page.on('pageerror', (e) => errors.push(String(e)));
  page.on('console', (m) => console.log(`page: ${m.text()}`));
  page.on('requestfailed', (r) => console.log(`page: request failed ${r.url()}`));
  await page.goto(url);
  const live = (expr) => page.evaluate(expr);
  const waitFor = async (expr, what, ms = 20000) => {
    const t0 = Date.now();
    while (Date.now() - t0 < ms) {
      if (await live(expr)) return;
      await sleep(50);
    }
    const st = await live("document.getElementById('status').textContent + ' | ' + " +
                          "document.getElementById('message').textContent + ' | ' + " +
                          "JSON.stringify(window.sinewLive && {frames: window.sinewLive.frames})");
    fail(`timed out waiting for ${what} (status: ${st}; page errors: ${errors.join('; ')})`);
  };
  await waitFor('window.sinewLive && window.sinewLive.frames > 5', 'frames');
  check(true, 'the page receives frames');

  // The muscle panel shows whole names: a long one (the face rig's) wraps instead of being cut
  // ("frontalis_l…" in a fixed 80 px box before issue 34).
  const nameFits = await live(`(() => { const e = document.querySelector('#muscles .name');
    const shown = e.textContent === 'flexor';
    e.textContent = 'frontalis_left_medial_and_lateral_bellies';
    const fits = e.scrollWidth <= e.clientWidth + 1;
    e.textContent = 'flexor';
    return shown && fits; })()`);
  check(nameFits, 'the muscle panel shows the whole muscle name, long ones wrapped');

  // Slider to 1: the free end (largest x) moves towards the clamp.
  const freeEndDx = `(() => { const L = window.sinewLive, r = L.rest(), d = L.displacement;
    let m = 0; for (let i = 0; i < r.length / 3; ++i) if (r[3*i] > 0.0239) m = Math.min(m, d[3*i]); return m; })()`;
  const before = await live(freeEndDx);
  await page.$eval('#muscles input', (s) => { s.value = '1'; s.dispatchEvent(new Event('input')); });
  await waitFor(`${freeEndDx} < ${before - 2e-4}`, 'the slider to contract the muscle');
  const after = await live(freeEndDx);
  check(after < before - 2e-4, `the slider contracts the muscle (free end x: ${before} -> ${after} m)`);
  // Let the contraction settle before picking a point 1 mm from the free end: on a loaded machine
  // the end moved on by millimetres between reading its position and pressing the mouse, and the
  // press missed the skin (seen in CI).
  let settled = false;
  for (let k = 0, last = after; k < 100 && !settled; ++k) {
    await sleep(300);
    const now = await live(freeEndDx);
    settled = Math.abs(now - last) < 1e-5;
    last = now;
  }
  check(settled, 'the contraction settles');

  // Drag the top of the free end upwards on the screen: the picked region rises (z).
  const topZ = `(() => { const L = window.sinewLive, r = L.rest(), d = L.displacement;
    let m = -1; for (let i = 0; i < r.length / 3; ++i) if (r[3*i] > 0.0235 && r[3*i+2] > 0.0059) m = Math.max(m, d[3*i+2]); return m; })()`;
  const z0 = await live(topZ);
  // The current position of the skin vertex at the middle of the free end's top edge.
  const [x, y] = await live(`(() => { const L = window.sinewLive, r = L.rest(), d = L.displacement;
    let best = -1; for (let i = 0; i < r.length / 3; ++i)
      if (r[3*i+2] > 0.0059 && Math.abs(r[3*i+1] - 0.004) < 1e-4 &&
          (best < 0 || r[3*i] > r[3*best])) best = i;
    return L.screenOf(r[3*best] + d[3*best] - 0.001, r[3*best+1] + d[3*best+1], r[3*best+2] + d[3*best+2]); })()`);
  // A gentle spring (2 N/m): the page's default 50 N/m pulling 120 px on this 3 kPa block inverts
  // elements when the drag is held a little longer (a loaded machine), and the test would see the
  // engine stop instead of the page working.
  await page.$eval('#stiffness', (s) => { s.value = '2'; s.dispatchEvent(new Event('input')); });
  await page.mouse.move(x, y);
  await page.mouse.down();
  for (let k = 1; k <= 10; ++k) { await page.mouse.move(x, y - 12 * k); await sleep(60); }
  await waitFor(`${topZ} > ${z0 + 2e-4}`, 'the drag to lift the picked region');
  const z1 = await live(topZ);
  await page.mouse.up();
  check(z1 > z0 + 2e-4, `dragging lifts the picked region (top z: ${z0} -> ${z1} m)`);

  // Pause: the step stops; resume: it goes on.
  await page.click('#pause');
  await waitFor('window.sinewLive.status && window.sinewLive.status.paused', 'pause');
  const s0 = await live('window.sinewLive.status.step');
  await sleep(600);
  check(await live('window.sinewLive.status.step') === s0, 'pause stops the engine');
  await page.click('#resume');
  await waitFor(`window.sinewLive.status.step > ${s0}`, 'resume');
  check(true, 'resume runs it on');

  // Record about a second, then stop.
  await page.click('#record');
  await waitFor('window.sinewLive.status.recording', 'recording');
  const recording = await live('window.sinewLive.status.recording');
  await sleep(1200);
  await page.click('#record');
  await waitFor('!window.sinewLive.status.recording', 'recording stopped');
  const rec = path.resolve(work, recording);
  check(fs.existsSync(path.join(rec, 'scene.yaml')), `the recording is in ${rec}`);
  check(!(await live('window.sinewLive.status.error')),
        `the engine ran on while recording (${await live("document.getElementById('message').textContent")})`);

  // The colour bar and a screenshot that is not blank.
  const shot = path.join(work, 'live.png');
  await page.screenshot({ path: shot });
  if (env.SCREENSHOT) fs.copyFileSync(shot, env.SCREENSHOT);
  const pixels = await live(`(() => {
    const c = document.querySelector('#view canvas'), t = document.createElement('canvas');
    t.width = c.width; t.height = c.height; const g = t.getContext('2d'); g.drawImage(c, 0, 0);
    const d = g.getImageData(0, 0, t.width, t.height).data, seen = new Set(); let lit = 0;
    for (let i = 0; i < d.length; i += 4 * 7) { const k = (d[i] << 16) | (d[i+1] << 8) | d[i+2];
      seen.add(k); if (k !== 0x30343c) ++lit; }
    const b = document.getElementById('bar').getContext('2d');
    const top = b.getImageData(10, 1, 1, 1).data, bottom = b.getImageData(10, 198, 1, 1).data;
    return { colours: seen.size, lit, bar: [Array.from(top), Array.from(bottom)],
             label: document.getElementById('bar_max').textContent }; })()`);
  check(pixels.colours > 50 && pixels.lit > 2000,
        `the screenshot is not blank (${pixels.colours} colours, ${pixels.lit} lit samples)`);
  check(pixels.bar[0].join() !== pixels.bar[1].join() && /mm/.test(pixels.label),
        `the colour bar is drawn and labelled (${pixels.label})`);
  check(errors.length === 0, `no page errors (${errors.join('; ')})`);

  // sinew-render reads the recording; the reproducing scene gives the same bits.
  run(env.SINEW_RENDER, [path.join(rec, 'results.h5'), '-o', path.join(work, 'render.png')]);
  check(fs.statSync(path.join(work, 'render.png')).size > 1000, 'sinew-render draws the recording');
  run(env.SINEW_SIMULATE, [path.join(rec, 'scene.yaml'), '-o', path.join(work, 'reproduced'),
                           '--device', 'cpu', '--threads', '1', '-q']);
  const cmp = run(env.LIVE_COMPARE, [path.join(rec, 'results.h5'),
                                     path.join(work, 'reproduced', 'results.h5')]);
  check(/ 0 differ/.test(cmp), `the reproduced scene gives the same bits (${cmp.trim()})`);

  // Playback of the recording: scrub to its last frame, colour it by the file's von Mises stress.
  await page.close();
  server.kill('SIGINT');
  player = spawn(env.SINEW_LIVE, ['--play', path.join(rec, 'results.h5'), '--device', 'cpu',
                                  '--threads', '1', '--port', '0'], { cwd: work });
  let played = '';
  player.stdout.on('data', (d) => { played += d; });
  player.stderr.on('data', (d) => { played += d; });
  for (let k = 0; k < 300 && !/open (http\S+)/.test(played); ++k) await sleep(50);
  const playUrl = (played.match(/open (http\S+)/) || [])[1];
  check(playUrl, `sinew-live --play printed its URL (${playUrl}; ${played.trim()})`);
  const view = await browser.newPage();
  await view.setViewport({ width: 1100, height: 700 });
  view.on('pageerror', (e) => errors.push(String(e)));
  await view.goto(playUrl);
  const shown = (expr) => view.evaluate(expr);
  const waitShown = async (expr, what) => {
    const t0 = Date.now();
    while (Date.now() - t0 < 20000) {
      if (await shown(expr)) return;
      await sleep(50);
    }
    fail(`timed out waiting for ${what} (page errors: ${errors.join('; ')})`);
  };
  await waitShown("window.sinewLive.frames > 0 && !document.getElementById('playback').hidden",
                  'the playback controls and a frame');
  const last = await shown("Number(document.getElementById('frame').max)");
  check(last > 0 && await shown("!document.querySelector('#field option[value=von_mises]').disabled"),
        `playback offers the file's ${last + 1} frames and its von Mises stress`);
  await view.$eval('#frame', (s) => { s.value = s.max; s.dispatchEvent(new Event('input')); });
  await waitShown(`window.sinewLive.status && window.sinewLive.status.playback.frame === ${last}`,
                  'the last frame');
  await view.select('#field', 'von_mises');
  await waitShown("window.sinewLive.field === 'von_mises' && window.sinewLive.max > 0",
                  'the von Mises colours');
  const bar = await shown("document.getElementById('bar_label').textContent + ': ' + " +
                          "document.getElementById('bar_max').textContent");
  check(/Pa/.test(bar), `the played-back frame is coloured by von Mises stress (${bar})`);
  // Continue from it: the scene replayed to the frame's step, then live there (paused), with the
  // engine's own von Mises colours.
  const fileStep = await shown('window.sinewLive.step');
  await view.click('#continue');
  await waitShown('window.sinewLive.status.playback === null && window.sinewLive.status.paused && ' +
                  `window.sinewLive.status.step === ${fileStep} && window.sinewLive.step === ${fileStep} && ` +
                  "window.sinewLive.field === 'von_mises' && document.getElementById('playback').hidden",
                  `continuing from the frame at step ${fileStep}`);
  check(fileStep > 0, `continue replays to the frame's step ${fileStep} and goes on live there`);
  check(errors.length === 0, `no page errors in playback (${errors.join('; ')})`);
} finally {
  if (browser) await browser.close();
  server.kill('SIGINT');
  if (player) player.kill('SIGINT');
}

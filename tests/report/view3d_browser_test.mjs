// The report's 3D view in headless Chromium, driven over the DevTools protocol (Node's WebSocket,
// no other package): a small synthetic run (objmap synth + fuse + report), its report.html opened
// from the file system. Asserts: no console error and no exception, the WebGL canvas draws the map
// (non-background pixels in a screenshot, none once every layer is off), a click on an object's
// label opens its panel with its class and id, the search highlights exactly the objects that
// `objmap query` returns for each phrase, and the page makes no network request.
//
//   node --experimental-websocket view3d_browser_test.mjs OBJMAP [KEEP_DIR]
// Exit 0: passed; 1: failed (each failure on stderr); 77: skipped (no chromium).
//   node --experimental-websocket view3d_browser_test.mjs --shoot REPORT.html OUT.png [SEARCH]
// A screenshot of the page's 3D view as a person sees it (labels, toolbar), after SEARCH if given,
// with the panel of the first label that nothing covers open; prints the load time and the time a
// frame takes while zooming.
import {spawn, spawnSync, execFileSync} from 'node:child_process';
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import zlib from 'node:zlib';

const objmap = process.argv[2];
const keep = process.argv[3];
const failures = [];
const started = Date.now();
function check(ok, what) {
  if (!ok) failures.push(what);
  console.log((ok ? 'ok    ' : 'FAIL  ') + what + ` (${((Date.now() - started) / 1000).toFixed(1)} s)`);
}

function findChromium() {
  for (const name of [process.env.CHROMIUM, 'chromium', 'chromium-browser', 'google-chrome']) {
    if (!name) continue;
    const found = spawnSync('sh', ['-c', 'command -v "$0"', name], {encoding: 'utf8'});
    if (found.status === 0 && found.stdout.trim()) return found.stdout.trim();
  }
  return null;
}

function run(args) {
  const r = spawnSync(objmap, args, {encoding: 'utf8'});
  if (r.status !== 0) throw new Error(`objmap ${args.join(' ')}: exit ${r.status}\n${r.stderr}`);
  return r.stdout;
}

// A PNG (8-bit RGB or RGBA, not interlaced) as {width, height, channels, pixels}.
function decodePng(buffer) {
  let at = 8, width = 0, height = 0, channels = 0;
  const idat = [];
  while (at < buffer.length) {
    const length = buffer.readUInt32BE(at), type = buffer.toString('latin1', at + 4, at + 8);
    const body = buffer.subarray(at + 8, at + 8 + length);
    if (type === 'IHDR') {
      width = body.readUInt32BE(0);
      height = body.readUInt32BE(4);
      if (body[8] !== 8 || body[12] !== 0) throw new Error('PNG: not 8-bit non-interlaced');
      channels = {2: 3, 6: 4}[body[9]];
      if (!channels) throw new Error('PNG: colour type ' + body[9]);
    } else if (type === 'IDAT') {
      idat.push(body);
    }
    at += 12 + length;
  }
  const raw = zlib.inflateSync(Buffer.concat(idat));
  const stride = width * channels, pixels = Buffer.alloc(height * stride);
  for (let y = 0; y < height; ++y) {
    const filter = raw[y * (stride + 1)], line = raw.subarray(y * (stride + 1) + 1);
    for (let x = 0; x < stride; ++x) {
      const a = x >= channels ? pixels[y * stride + x - channels] : 0;
      const b = y > 0 ? pixels[(y - 1) * stride + x] : 0;
      const c = x >= channels && y > 0 ? pixels[(y - 1) * stride + x - channels] : 0;
      const p = a + b - c, pa = Math.abs(p - a), pb = Math.abs(p - b), pc = Math.abs(p - c);
      const predictor = [0, a, b, (a + b) >> 1, pa <= pb && pa <= pc ? a : pb <= pc ? b : c][filter];
      pixels[y * stride + x] = (line[x] + predictor) & 0xff;
    }
  }
  return {width, height, channels, pixels};
}

// The share of pixels that differ from the view's background (#f4f5f7) by more than 12.
function foregroundShare(png) {
  let n = 0;
  for (let i = 0; i < png.width * png.height; ++i) {
    const o = i * png.channels, p = png.pixels;
    if (Math.abs(p[o] - 0xf4) + Math.abs(p[o + 1] - 0xf5) + Math.abs(p[o + 2] - 0xf7) > 12) ++n;
  }
  return n / (png.width * png.height);
}

class Cdp {
  constructor(url) {
    this.ws = new WebSocket(url);
    this.next = 1;
    this.waiting = new Map();
    this.listeners = [];
    this.ws.onmessage = (m) => {
      const msg = JSON.parse(m.data);
      if (msg.id && this.waiting.has(msg.id)) {
        const {resolve, reject} = this.waiting.get(msg.id);
        this.waiting.delete(msg.id);
        msg.error ? reject(new Error(JSON.stringify(msg.error))) : resolve(msg.result);
      } else if (msg.method) {
        for (const l of this.listeners) l(msg);
      }
    };
  }
  open() {
    return new Promise((resolve, reject) => {
      this.ws.onopen = resolve;
      this.ws.onerror = reject;
    });
  }
  send(method, params = {}) {
    const id = this.next++;
    this.ws.send(JSON.stringify({id, method, params}));
    return new Promise((resolve, reject) => this.waiting.set(id, {resolve, reject}));
  }
  async evaluate(expression) {
    const r = await this.send('Runtime.evaluate', {expression, returnByValue: true,
                                                   awaitPromise: true});
    if (r.exceptionDetails) throw new Error(expression + ': ' + JSON.stringify(r.exceptionDetails));
    return r.result.value;
  }
}

const sleep = (ms) => new Promise((r) => setTimeout(r, ms));
async function until(what, predicate, timeoutMs = 45000) {
  const start = Date.now();
  for (;;) {
    const v = await predicate();
    if (v) return v;
    if (Date.now() - start > timeoutMs) throw new Error('timed out waiting for ' + what);
    await sleep(50);
  }
}

async function screenshotOfView(cdp) {
  // Overlays (toolbar, labels, help) hidden: the pixels are the WebGL canvas's.
  await cdp.evaluate(`(() => { for (const s of ['.toolbar', '.labels', '.help', '.panel'])
      document.querySelector('#view3d ' + s).style.visibility = 'hidden'; })()`);
  const r = await cdp.evaluate(`(() => { const v = document.getElementById('view3d'), b =
      v.getBoundingClientRect(); return {x: b.x + scrollX + v.clientLeft, y: b.y + scrollY +
      v.clientTop, width: v.clientWidth, height: v.clientHeight}; })()`);  // inside the border
  const shot = await cdp.send('Page.captureScreenshot', {format: 'png', captureBeyondViewport: true,
                                                         clip: {...r, scale: 1}});
  await cdp.evaluate(`(() => { for (const s of ['.toolbar', '.labels', '.help', '.panel'])
      document.querySelector('#view3d ' + s).style.visibility = ''; })()`);
  return Buffer.from(shot.data, 'base64');
}

// The share of pixels that differ by more than 24 between two screenshots of one size.
function changedShare(a, b) {
  let n = 0;
  for (let i = 0; i < a.width * a.height; ++i) {
    const o = i * a.channels;
    if (Math.abs(a.pixels[o] - b.pixels[o]) + Math.abs(a.pixels[o + 1] - b.pixels[o + 1]) +
        Math.abs(a.pixels[o + 2] - b.pixels[o + 2]) > 24)
      ++n;
  }
  return n / (a.width * a.height);
}

async function dragBy(cdp, from, dx, dy) {
  await cdp.send('Input.dispatchMouseEvent', {type: 'mousePressed', x: from.x, y: from.y,
                                              button: 'left', buttons: 1, clickCount: 1});
  for (let k = 1; k <= 4; ++k)
    await cdp.send('Input.dispatchMouseEvent', {type: 'mouseMoved', x: from.x + dx * k / 4,
                                                y: from.y + dy * k / 4, button: 'left',
                                                buttons: 1});
  await cdp.send('Input.dispatchMouseEvent', {type: 'mouseReleased', x: from.x + dx,
                                              y: from.y + dy, button: 'left', buttons: 0,
                                              clickCount: 1});
  await sleep(300);
}

async function setLayers(cdp, on) {
  const frames = await cdp.evaluate(`Number(document.getElementById('view3d').dataset.frames)`);
  await cdp.evaluate(`(() => { for (const i of document.querySelectorAll('#view3d input[data-layer]'))
      { const want = ${JSON.stringify(on)}.includes(i.dataset.layer); if (i.checked !== want)
        i.click(); } })()`);
  await until('a redraw', async () =>
    (await cdp.evaluate(`Number(document.getElementById('view3d').dataset.frames)`)) > frames);
}

// Chromium (headless, software WebGL) with `html` open and drawn: {cdp, errors, requests, close}.
// errors: console errors and exceptions; requests: every URL fetched but the page and data:/blob:.
async function openPage(chromium, html) {
  const profile = fs.mkdtempSync(path.join(os.tmpdir(), 'objmap-chromium-'));
  const browser = spawn(chromium, [
    '--headless=new', '--use-gl=swiftshader', '--enable-unsafe-swiftshader', '--no-sandbox',
    '--no-first-run', '--no-default-browser-check', '--disable-extensions', '--disable-breakpad',
    '--disable-crash-reporter',
    '--remote-debugging-port=0', '--user-data-dir=' + profile, '--window-size=1000,900',
    'about:blank'], {stdio: ['ignore', 'ignore', 'pipe'], detached: true});
  const exited = new Promise((resolve) => browser.on('exit', resolve));
  browser.stderr.on('data', () => {});
  const killGroup = () => {
    try {
      process.kill(-browser.pid, 'SIGKILL');  // chromium and its children (its process group)
    } catch (e) {
    }
  };
  process.on('exit', killGroup);  // also when the script ends early (a timeout, a failure)
  const close = async () => {
    killGroup();
    await exited;
    fs.rmSync(profile, {recursive: true, force: true, maxRetries: 10, retryDelay: 100});
  };
  try {
    const portFile = path.join(profile, 'DevToolsActivePort');
    const port = await until('DevToolsActivePort', () =>
      fs.existsSync(portFile) && fs.readFileSync(portFile, 'utf8').split('\n')[0]);
    const targets = await until('a page target', async () => {
      const list = await (await fetch(`http://127.0.0.1:${port}/json/list`)).json();
      return list.find((t) => t.type === 'page');
    });
    const cdp = new Cdp(targets.webSocketDebuggerUrl);
    await cdp.open();
    const errors = [], requests = [];
    const pageUrl = 'file://' + path.resolve(html);
    cdp.listeners.push((m) => {
      if (m.method === 'Runtime.consoleAPICalled' && (m.params.type === 'error' ||
                                                      m.params.type === 'assert'))
        errors.push('console: ' + m.params.args.map((a) => a.value ?? a.description).join(' '));
      if (m.method === 'Runtime.exceptionThrown')
        errors.push('exception: ' + m.params.exceptionDetails.exception?.description);
      if (m.method === 'Log.entryAdded' && m.params.entry.level === 'error')
        errors.push('log: ' + m.params.entry.text);
      if (m.method === 'Network.requestWillBeSent') {
        const url = m.params.request.url;
        if (url !== pageUrl && !url.startsWith('data:') && !url.startsWith('blob:'))
          requests.push(url);
      }
    });
    for (const domain of ['Runtime', 'Network', 'Page', 'Log']) await cdp.send(domain + '.enable');
    const loaded = new Promise((resolve) => cdp.listeners.push((m) => {
      if (m.method === 'Page.loadEventFired') resolve();
    }));
    const t0 = Date.now();
    await cdp.send('Page.navigate', {url: pageUrl});
    await loaded;
    await until('the first frame', () =>
      cdp.evaluate(`Number(document.getElementById('view3d')?.dataset.frames || 0) > 0`));
    console.log(`page loaded and drawn in ${Date.now() - t0} ms`);
    await cdp.evaluate(`document.getElementById('view3d').scrollIntoView()`);
    return {cdp, errors, requests, close};
  } catch (e) {
    await close();
    throw e;
  }
}

// The first label that nothing covers: {id, text, x, y} (its centre), or null.
function uncoveredLabel(cdp) {
  return cdp.evaluate(`(() => { for (const l of document.querySelectorAll(
      '#view3d .label')) { const b = l.getBoundingClientRect(); const x = b.x + b.width / 2,
      y = b.y + b.height / 2; if (l.style.display !== 'none' && document.elementFromPoint(x, y)
      === l) return {id: Number(l.dataset.id), text: l.textContent, x, y}; } return null; })()`);
}

async function clickAt(cdp, x, y) {
  for (const type of ['mousePressed', 'mouseReleased'])
    await cdp.send('Input.dispatchMouseEvent', {type, x, y, button: 'left', clickCount: 1});
}

function searchFor(cdp, text) {  // the ids of the labels highlighted
  return cdp.evaluate(`(() => { const s = document.querySelector('#view3d input[type=search]');
      s.value = ${JSON.stringify(text)}; s.dispatchEvent(new Event('input')); return [
      ...document.querySelectorAll('#view3d .label.hit')].map((l) => Number(l.dataset.id))
      .sort((a, b) => a - b); })()`);
}

// --shoot: the view as a person sees it.
async function shoot(chromium, html, out, text) {
  const page = await openPage(chromium, html);
  try {
    const timing = await page.cdp.evaluate(`new Promise((done) => { const v = document
        .getElementById('view3d'); const f0 = Number(v.dataset.frames), t0 = performance.now();
        let n = 0; const step = () => { v.dispatchEvent(new WheelEvent('wheel', {deltaY: n < 15 ?
        2 : -2, bubbles: true, cancelable: true})); if (++n < 30) requestAnimationFrame(step);
        else requestAnimationFrame(() => done({frames: Number(v.dataset.frames) - f0,
        ms: performance.now() - t0})); }; step(); })`);
    console.log(`${timing.frames} frames while zooming in ${timing.ms.toFixed(0)} ms: ` +
                `${(timing.ms / timing.frames).toFixed(1)} ms a frame`);
    if (text) console.log(`search "${text}": ${JSON.stringify(await searchFor(page.cdp, text))}`);
    const label = await uncoveredLabel(page.cdp);
    if (label) await clickAt(page.cdp, label.x, label.y);
    await sleep(300);
    const r = await page.cdp.evaluate(`(() => { const b = document.getElementById('view3d')
        .getBoundingClientRect(); return {x: b.x + scrollX, y: b.y + scrollY, width: b.width,
        height: b.height}; })()`);
    const shot = await page.cdp.send('Page.captureScreenshot', {format: 'png', clip: {...r,
                                                                scale: 1}});
    fs.writeFileSync(out, Buffer.from(shot.data, 'base64'));
    console.log('errors ' + JSON.stringify(page.errors) + ', requests ' +
                JSON.stringify(page.requests));
  } finally {
    await page.close();
  }
}

async function main() {
  const chromium = findChromium();
  if (!chromium) {
    console.log('skipped: no chromium (Debian package chromium; scripts/install-deps.sh)');
    process.exit(77);
  }
  const dir = keep || fs.mkdtempSync(path.join(os.tmpdir(), 'objmap-view3d-'));
  fs.mkdirSync(dir, {recursive: true});
  const scene = path.join(dir, 'scene'), runDir = path.join(dir, 'run');
  fs.rmSync(scene, {recursive: true, force: true});
  fs.rmSync(runDir, {recursive: true, force: true});
  run(['synth', '--out', scene, '--seed', '3', '--frames', '12']);
  run(['fuse', '--dataset', scene, '--trajectory', path.join(scene, 'groundtruth.txt'),
       '--segmentation', path.join(scene, 'segmentation'), '--out', runDir]);
  run(['report', '--run', runDir]);
  const html = path.join(runDir, 'report', 'report.html');
  const phrases = ['cup', 'cups on table', 'book on book', 'books on the table', 'chair on floor',
                   'cup near keyboard', 'mouse above floor', 'chair on table', 'tv on surface'];
  const opening = openPage(chromium, html);  // chromium starts while objmap answers the queries
  const expected = {};
  for (const q of phrases)
    expected[q] = JSON.parse(run(['query', '--run', runDir, q, '--json'])).matches
                      .map((m) => m.id).sort((a, b) => a - b);
  check(Object.values(expected).some((ids) => ids.length > 1) &&
        Object.values(expected).some((ids) => ids.length === 0),
        'the phrases include ones with several matches and ones with none');

  const page = await opening;
  const cdp = page.cdp;
  try {

    // The canvas draws: all layers, the map alone, nothing.
    const allPng = await screenshotOfView(cdp);
    if (keep) fs.writeFileSync(path.join(dir, 'view3d.png'), allPng);
    const all = decodePng(allPng);
    await setLayers(cdp, ['map']);
    const mapOnly = foregroundShare(decodePng(await screenshotOfView(cdp)));
    await setLayers(cdp, []);
    const none = foregroundShare(decodePng(await screenshotOfView(cdp)));
    await setLayers(cdp, ['map', 'objects', 'boxes', 'labels', 'surfaces', 'path']);
    console.log(`foreground: all layers ${foregroundShare(all).toFixed(3)}, map ` +
                `${mapOnly.toFixed(3)}, none ${none.toFixed(4)} (${all.width}x${all.height})`);
    check(mapOnly > 0.05, 'the map alone covers more than 5% of the view');
    check(foregroundShare(all) >= mapOnly, 'all layers cover at least what the map covers');
    check(none < 0.002, 'with every layer off the view is background');

    // Orbit (drag) turns the picture; the wheel zooms in (more of the view covered).
    const centre = await cdp.evaluate(`(() => { const b = document.querySelector('#view3d canvas')
        .getBoundingClientRect(); return {x: b.x + b.width / 2, y: b.y + b.height / 2}; })()`);
    await dragBy(cdp, centre, 160, 40);
    const turned = decodePng(await screenshotOfView(cdp));
    const changed = changedShare(all, turned);
    await cdp.send('Input.dispatchMouseEvent', {type: 'mouseWheel', x: centre.x, y: centre.y,
                                                deltaX: 0, deltaY: -500});
    await sleep(300);
    const zoomed = foregroundShare(decodePng(await screenshotOfView(cdp)));
    console.log(`orbit changed ${changed.toFixed(3)} of the pixels; zoom: foreground ` +
                `${foregroundShare(turned).toFixed(3)} -> ${zoomed.toFixed(3)}`);
    check(changed > 0.02, 'dragging orbits the view (the picture changes)');
    check(zoomed > foregroundShare(turned) * 1.2, 'the wheel zooms in (more of the view covered)');

    // A click on a label that nothing covers opens its object's panel.
    const label = await uncoveredLabel(cdp);
    check(label !== null, 'some object label is visible and uncovered');
    if (label) {
      await clickAt(cdp, label.x, label.y);
      const panel = await cdp.evaluate(`(() => { const p = document.querySelector(
          '#view3d .panel'); return {open: p.classList.contains('open'), id: p.dataset.id,
          title: p.querySelector('h3')?.textContent, text: p.textContent,
          thumb: !!p.querySelector('img')}; })()`);
      const [id, ...cls] = label.text.split(' ');
      check(panel.open && Number(panel.id) === label.id, `clicking label "${label.text}" opens ` +
            `its panel (open ${panel.open}, id ${panel.id})`);
      check(panel.title === `${cls.join(' ')} (id ${id})`, `the panel's title "${panel.title}"`);
      check(/position .* m/.test(panel.text) && /size \d+ × \d+ × \d+ cm/.test(panel.text) &&
            /observations/.test(panel.text) && panel.thumb,
            'the panel shows position, size, observations and the thumbnail');
    }

    // The search highlights exactly what `objmap query` returns.
    for (const q of phrases) {
      const got = await searchFor(cdp, q);
      check(JSON.stringify(got) === JSON.stringify(expected[q]),
            `search "${q}": page ${JSON.stringify(got)}, objmap query ` +
            JSON.stringify(expected[q]));
    }
    await sleep(200);
    check(page.errors.length === 0, 'no console error: ' + JSON.stringify(page.errors));
    check(page.requests.length === 0, 'no network request: ' + JSON.stringify(page.requests));
  } finally {
    await page.close();
    if (!keep) fs.rmSync(dir, {recursive: true, force: true});
  }
}

// A watchdog well inside ctest's 240 s: the run it builds takes ~10 s on a free machine, ~60 s
// under make sanitize (ASan) or a loaded one; this bounds a hang, not the speed.
const timer = setTimeout(() => {
  console.error('FAIL  timed out after 200 s');
  process.exit(1);
}, 200000);
const work = process.argv[2] === '--shoot' ?
    shoot(findChromium(), process.argv[3], process.argv[4], process.argv[5]) : main();
work.then(() => {
  clearTimeout(timer);
  if (failures.length) {
    console.error(failures.length + ' check(s) failed');
    process.exit(1);
  }
  process.exit(0);
}, (e) => {
  console.error('FAIL  ' + (e.stack || e));
  process.exit(1);
});

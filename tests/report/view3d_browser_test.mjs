// The report's 3D view in headless Chromium, driven over the DevTools protocol (Node's WebSocket,
// no other package): a small synthetic run (objmap synth + fuse + report), its report.html opened
// from the file system. Asserts: no console error and no exception, the WebGL canvas draws the map
// (non-background pixels in a screenshot, none once every layer is off), a click on an object's
// label opens its panel with its class and id, the search highlights exactly the objects that
// `objmap query` returns for each phrase, and the page makes no network request.
// On a loaded machine: Chromium's port is read from its stderr (or its complete DevToolsActivePort
// file), listeners are attached before the events can fire, every wait polls the page's own state
// (frames drawn, inputs handled) within a time limit, no fixed sleep; a failure names its step.
//
//   node --experimental-websocket view3d_browser_test.mjs OBJMAP [KEEP_DIR]
// Exit 0: passed; 1: failed (each failure on stderr); 77: skipped (no chromium).
//   node --experimental-websocket view3d_browser_test.mjs --shoot REPORT.html OUT.png [SEARCH]
// A screenshot of the page's 3D view as a person sees it (labels, toolbar), after SEARCH if given,
// with the panel of the first label that nothing covers open; prints the load time and the time a
// frame takes while zooming.
import {execFile, spawn, spawnSync} from 'node:child_process';
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import {pathToFileURL} from 'node:url';
import zlib from 'node:zlib';

const objmap = process.argv[2];
const keep = process.argv[3];
const failures = [];
const started = Date.now();
// What the test is waiting for now: every wait is bounded and its failure (and the watchdog's)
// names this step.
let step = 'starting';
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

// As run(), without blocking Node's event loop (Chromium is driven meanwhile).
function runAsync(args) {
  return new Promise((resolve, reject) => execFile(objmap, args, {encoding: 'utf8'},
                                                   (error, stdout, stderr) => {
    if (error) reject(new Error(`objmap ${args.join(' ')}: exit ${error.code}\n${stderr}`));
    else resolve(stdout);
  }));
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

// The DevTools protocol over one WebSocket. Every command is answered or fails: a timeout naming
// the command, or the connection's end (chromium exited, the page crashed) failing all pending.
class Cdp {
  constructor(url) {
    this.ws = new WebSocket(url);
    this.next = 1;
    this.waiting = new Map();
    this.listeners = [];
    this.broken = null;  // why no answer can come any more
    this.opened = new Promise((resolve, reject) => {
      this.ws.onopen = resolve;
      this.ws.onerror = () => reject(new Error('could not connect to ' + url));
    });
    this.opened.catch(() => {});  // awaited by the caller; a failure later is the onclose's
    this.ws.onclose = () => this.fail('the DevTools connection closed');
    this.ws.onmessage = (m) => {
      const msg = JSON.parse(m.data);
      if (msg.id && this.waiting.has(msg.id)) {
        const {resolve, reject} = this.waiting.get(msg.id);
        this.waiting.delete(msg.id);
        msg.error ? reject(new Error(JSON.stringify(msg.error))) : resolve(msg.result);
      } else if (msg.method) {
        if (msg.method === 'Inspector.targetCrashed') this.fail('the page crashed');
        for (const l of this.listeners) l(msg);
      }
    };
  }
  fail(why) {
    if (this.broken) return;
    this.broken = why;
    for (const [, {method, reject}] of this.waiting) reject(new Error(`${method}: ${why}`));
    this.waiting.clear();
  }
  send(method, params = {}, timeoutMs = 60000) {
    if (this.broken) return Promise.reject(new Error(`${method}: ${this.broken}`));
    const id = this.next++;
    return new Promise((resolve, reject) => {
      const timer = setTimeout(() => {
        this.waiting.delete(id);
        reject(new Error(`${method}: no answer in ${timeoutMs / 1000} s`));
      }, timeoutMs);
      const done = (f) => (v) => {
        clearTimeout(timer);
        f(v);
      };
      this.waiting.set(id, {method, resolve: done(resolve), reject: done(reject)});
      this.ws.send(JSON.stringify({id, method, params}));
    });
  }
  async evaluate(expression) {
    const r = await this.send('Runtime.evaluate', {expression, returnByValue: true,
                                                   awaitPromise: true});
    if (r.exceptionDetails) throw new Error(expression + ': ' + JSON.stringify(r.exceptionDetails));
    return r.result.value;
  }
}

const sleep = (ms) => new Promise((r) => setTimeout(r, ms));
// Polls `predicate` until it returns a truthy value (returned). `tolerate`: an exception is a "not
// yet" (a page being replaced, a port not yet listening); otherwise it ends the wait.
async function until(what, predicate, {timeoutMs = 60000, tolerate = false} = {}) {
  const start = Date.now();
  let lastError = null;
  for (;;) {
    try {
      const v = await predicate();
      if (v) return v;
    } catch (e) {
      if (!tolerate) throw e;
      lastError = e;
    }
    if (Date.now() - start > timeoutMs)
      throw new Error(`timed out after ${timeoutMs / 1000} s waiting for ${what}` +
                      (lastError ? ` (last error: ${lastError.message})` : ''));
    await sleep(50);
  }
}

const framesDrawn = (cdp) =>
  cdp.evaluate(`Number(document.getElementById('view3d')?.dataset.frames || 0)`);

// Resolves once the page has run two animation frames: a redraw asked for before (the view draws
// in requestAnimationFrame) has been drawn.
function settled(cdp) {
  return cdp.evaluate(`new Promise((done) => requestAnimationFrame(() =>
      requestAnimationFrame(() => done(true))))`);
}

// Input.dispatchMouseEvent events, then waits until the page has handled the last one (a counter
// of its DOM event, kept by a capturing listener on window since the page loaded) and drawn after.
const domEventOf = {mousePressed: 'pointerdown', mouseReleased: 'pointerup', mouseWheel: 'wheel'};
async function dispatch(cdp, events) {
  const type = domEventOf[events[events.length - 1].type];
  const count = `(window.objmapTestSeen[${JSON.stringify(type)}] || 0)`;
  const before = await cdp.evaluate(count);
  for (const e of events) await cdp.send('Input.dispatchMouseEvent', e);
  await until(`the page to handle the ${type}`, async () => (await cdp.evaluate(count)) > before);
  await settled(cdp);
}

// A PNG screenshot (Page.captureScreenshot with `params`) once two captures in a row are alike:
// the picture has settled (a single capture on a loaded machine once showed the map on a black
// background instead of the view's own).
async function settledScreenshot(cdp, params) {
  let last = null;
  return until('two screenshots alike', async () => {
    const shot = await cdp.send('Page.captureScreenshot', {format: 'png', ...params});
    const now = Buffer.from(shot.data, 'base64'), same = last !== null && now.equals(last);
    last = now;
    return same && now;
  });
}

async function screenshotOfView(cdp) {
  // Overlays (toolbar, labels, help) hidden: the pixels are the WebGL canvas's.
  await cdp.evaluate(`(() => { for (const s of ['.toolbar', '.labels', '.help', '.panel'])
      document.querySelector('#view3d ' + s).style.visibility = 'hidden'; })()`);
  const r = await cdp.evaluate(`(() => { const v = document.getElementById('view3d'), b =
      v.getBoundingClientRect(); return {x: b.x + scrollX + v.clientLeft, y: b.y + scrollY +
      v.clientTop, width: v.clientWidth, height: v.clientHeight}; })()`);  // inside the border
  const png = await settledScreenshot(cdp, {captureBeyondViewport: true, clip: {...r, scale: 1}});
  await cdp.evaluate(`(() => { for (const s of ['.toolbar', '.labels', '.help', '.panel'])
      document.querySelector('#view3d ' + s).style.visibility = ''; })()`);
  return png;
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

function dragBy(cdp, from, dx, dy) {
  const events = [{type: 'mousePressed', x: from.x, y: from.y, button: 'left', buttons: 1,
                   clickCount: 1}];
  for (let k = 1; k <= 4; ++k)
    events.push({type: 'mouseMoved', x: from.x + dx * k / 4, y: from.y + dy * k / 4,
                 button: 'left', buttons: 1});
  events.push({type: 'mouseReleased', x: from.x + dx, y: from.y + dy, button: 'left', buttons: 0,
               clickCount: 1});
  return dispatch(cdp, events);
}

// Turns the layers `on` on and the others off, and waits for a frame drawn after (the frame count
// is read in the same script as the clicks, so a frame counted later shows them).
async function setLayers(cdp, on) {
  const before = await cdp.evaluate(`(() => { let clicked = false; for (const i of document
      .querySelectorAll('#view3d input[data-layer]')) { const want = ${JSON.stringify(on)}
      .includes(i.dataset.layer); if (i.checked !== want) { i.click(); clicked = true; } }
      return clicked ? Number(document.getElementById('view3d').dataset.frames) : -1; })()`);
  if (before >= 0)
    await until(`a frame with the layers [${on}]`, async () => (await framesDrawn(cdp)) > before);
}

// Chromium (headless, software WebGL) started with a fresh profile: {browser, port, exited,
// why(), close()}. The DevTools port is read from the line Chromium prints once it listens (or from
// its DevToolsActivePort file, once both of its lines are written); port rejects when Chromium
// exits first, with the end of its stderr.
function startChromium(chromium) {
  const profile = fs.mkdtempSync(path.join(os.tmpdir(), 'objmap-chromium-'));
  const browser = spawn(chromium, [
    '--headless=new', '--use-gl=swiftshader', '--enable-unsafe-swiftshader', '--no-sandbox',
    '--no-first-run', '--no-default-browser-check', '--disable-extensions', '--disable-breakpad',
    '--disable-crash-reporter',
    '--remote-debugging-port=0', '--user-data-dir=' + profile, '--window-size=1000,900',
    'about:blank'], {stdio: ['ignore', 'ignore', 'pipe'], detached: true});
  let stderr = '', exitCode;
  const why = () =>
    `chromium exited (${exitCode}): ` + stderr.trim().split('\n').slice(-5).join(' | ');
  const exited = new Promise((resolve) => browser.on('exit', (code, signal) => {
    exitCode = signal || code;
    resolve();
  }));
  let poll;
  const port = new Promise((resolve, reject) => {
    browser.stderr.setEncoding('utf8');
    browser.stderr.on('data', (d) => {
      stderr = (stderr + d).slice(-20000);
      const m = /DevTools listening on ws:\/\/[^:/]+:(\d+)\//.exec(stderr);
      if (m) resolve(m[1]);
    });
    const portFile = path.join(profile, 'DevToolsActivePort');
    poll = setInterval(() => {
      const lines = fs.existsSync(portFile) ? fs.readFileSync(portFile, 'utf8').split('\n') : [];
      if (lines.length >= 2 && /^\d+$/.test(lines[0]) && lines[1].startsWith('/devtools/'))
        resolve(lines[0]);
    }, 100);
    exited.then(() => reject(new Error(why())));
  });
  port.then(() => clearInterval(poll), () => clearInterval(poll));  // the caller awaits port
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
  return {browser, port, exited, why, close};
}

// Resolves `promise`, or rejects after timeoutMs naming `what`.
function within(what, promise, timeoutMs = 60000) {
  let timer;
  const timeout = new Promise((_, reject) => {
    timer = setTimeout(() => reject(new Error(`timed out after ${timeoutMs / 1000} s waiting ` +
                                              `for ${what}`)), timeoutMs);
  });
  return Promise.race([promise, timeout]).finally(() => clearTimeout(timer));
}

// Chromium with `html` open and drawn: {cdp, errors, requests, close}. errors: console errors and
// exceptions; requests: every URL fetched but the page and data:/blob:.
async function openPage(chromium, html) {
  step = 'starting chromium';
  const browser = startChromium(chromium);
  try {
    step = "chromium's DevTools port";
    const port = await within(step, browser.port);
    step = "chromium's page target";
    const target = await until(step, async () => {
      const list = await (await fetch(`http://127.0.0.1:${port}/json/list`)).json();
      return list.find((t) => t.type === 'page');
    }, {tolerate: true});
    step = 'the DevTools connection to the page';
    const cdp = new Cdp(target.webSocketDebuggerUrl);
    browser.exited.then(() => cdp.fail(browser.why()));
    await within(step, cdp.opened);
    // Listening before the domains are enabled and the page is opened: no event is missed.
    const errors = [], requests = [];
    const pageUrl = pathToFileURL(path.resolve(html)).href;
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
    step = 'enabling the DevTools domains';
    for (const domain of ['Inspector', 'Runtime', 'Network', 'Page', 'Log'])
      await cdp.send(domain + '.enable');
    // The inputs the page has handled, counted from its first script on (dispatch() waits on them).
    await cdp.send('Page.addScriptToEvaluateOnNewDocument', {source: `window.objmapTestSeen = {};
        for (const t of ['pointerdown', 'pointerup', 'wheel']) addEventListener(t, () =>
          { objmapTestSeen[t] = (objmapTestSeen[t] || 0) + 1; }, true);`});
    const t0 = Date.now();
    step = 'report.html to load';
    const nav = await cdp.send('Page.navigate', {url: pageUrl});
    if (nav.errorText) throw new Error(`opening ${pageUrl}: ${nav.errorText}`);
    // Polled, not an event: the load event of about:blank or of this page may come before or
    // after a listener would be attached; the page's own state says when it is ready.
    step = "report.html loaded and its 3D view's first frame";
    await until(step, () => cdp.evaluate(`location.href === ${JSON.stringify(pageUrl)} &&
        document.readyState === 'complete' && !!window.objmapTestSeen &&
        Number(document.getElementById('view3d')?.dataset.frames || 0) > 0`), {tolerate: true});
    console.log(`page loaded and drawn in ${Date.now() - t0} ms`);
    await cdp.evaluate(`document.getElementById('view3d').scrollIntoView()`);
    await settled(cdp);
    return {cdp, errors, requests, close: browser.close};
  } catch (e) {
    await browser.close();
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

function clickAt(cdp, x, y) {
  return dispatch(cdp, ['mousePressed', 'mouseReleased'].map((type) => ({type, x, y,
                                                                        button: 'left',
                                                                        clickCount: 1})));
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
    const r = await page.cdp.evaluate(`(() => { const b = document.getElementById('view3d')
        .getBoundingClientRect(); return {x: b.x + scrollX, y: b.y + scrollY, width: b.width,
        height: b.height}; })()`);
    fs.writeFileSync(out, await settledScreenshot(page.cdp, {clip: {...r, scale: 1}}));
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
  step = 'the synthetic run (objmap synth, fuse, report)';
  run(['synth', '--out', scene, '--seed', '3', '--frames', '12']);
  run(['fuse', '--dataset', scene, '--trajectory', path.join(scene, 'groundtruth.txt'),
       '--segmentation', path.join(scene, 'segmentation'), '--out', runDir]);
  run(['report', '--run', runDir]);
  const html = path.join(runDir, 'report', 'report.html');
  const phrases = ['cup', 'cups on table', 'book on book', 'books on the table', 'chair on floor',
                   'cup near keyboard', 'mouse above floor', 'chair on table', 'tv on surface'];
  // Chromium starts while objmap answers the queries (without blocking the event loop, so that
  // the page's waits and their time limits run meanwhile).
  const opening = openPage(chromium, html);
  opening.catch(() => {});  // awaited below
  const expected = {};
  for (const q of phrases)
    expected[q] = JSON.parse(await runAsync(['query', '--run', runDir, q, '--json'])).matches
                      .map((m) => m.id).sort((a, b) => a - b);
  check(Object.values(expected).some((ids) => ids.length > 1) &&
        Object.values(expected).some((ids) => ids.length === 0),
        'the phrases include ones with several matches and ones with none');

  const page = await opening;
  const cdp = page.cdp;
  try {

    // The canvas draws: all layers, the map alone, nothing.
    step = 'screenshots with all layers, the map alone, none';
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
    step = 'orbit and zoom';
    const centre = await cdp.evaluate(`(() => { const b = document.querySelector('#view3d canvas')
        .getBoundingClientRect(); return {x: b.x + b.width / 2, y: b.y + b.height / 2}; })()`);
    await dragBy(cdp, centre, 160, 40);
    const turned = decodePng(await screenshotOfView(cdp));
    const changed = changedShare(all, turned);
    await dispatch(cdp, [{type: 'mouseWheel', x: centre.x, y: centre.y, deltaX: 0,
                          deltaY: -500}]);
    const zoomed = foregroundShare(decodePng(await screenshotOfView(cdp)));
    console.log(`orbit changed ${changed.toFixed(3)} of the pixels; zoom: foreground ` +
                `${foregroundShare(turned).toFixed(3)} -> ${zoomed.toFixed(3)}`);
    check(changed > 0.02, 'dragging orbits the view (the picture changes)');
    check(zoomed > foregroundShare(turned) * 1.2, 'the wheel zooms in (more of the view covered)');

    // A click on a label that nothing covers opens its object's panel.
    step = "a label's panel";
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
    step = 'the search';
    for (const q of phrases) {
      const got = await searchFor(cdp, q);
      check(JSON.stringify(got) === JSON.stringify(expected[q]),
            `search "${q}": page ${JSON.stringify(got)}, objmap query ` +
            JSON.stringify(expected[q]));
    }
    await settled(cdp);  // an error the last input caused has been reported before this answer
    check(page.errors.length === 0, 'no console error: ' + JSON.stringify(page.errors));
    check(page.requests.length === 0, 'no network request: ' + JSON.stringify(page.requests));
  } finally {
    await page.close();
    if (!keep) fs.rmSync(dir, {recursive: true, force: true});
  }
}

// A watchdog well inside ctest's 240 s: the run it builds takes ~10 s on a free machine, ~60 s
// under make sanitize (ASan) or a loaded one; this bounds a hang, not the speed. Each wait has its
// own limit (60 s) and names its step; this one names the step it stopped in.
const timer = setTimeout(() => {
  console.error(`FAIL  timed out after 200 s; the step that did not finish: ${step}`);
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
  console.error(`FAIL  at the step "${step}": ` + (e.stack || e));
  process.exit(1);
});

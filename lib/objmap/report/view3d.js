// The report's 3D view (lib/objmap/report/view3d.h): reads the data of #view3d-data and draws it
// with three.js (the global THREE inlined before this script). z is up (the run's gravity frame).
(function () {
  const root = document.getElementById('view3d');
  const data = JSON.parse(document.getElementById('view3d-data').textContent);
  const canvas = root.querySelector('canvas');
  const labelsBox = root.querySelector('.labels');
  const panel = root.querySelector('.panel');
  const search = root.querySelector('input[type=search]');
  const searchResult = root.querySelector('.search-result');

  // --- data -------------------------------------------------------------------------------
  function bytesOf(base64) {
    const bin = atob(base64);
    const out = new Uint8Array(bin.length);
    for (let i = 0; i < bin.length; ++i) out[i] = bin.charCodeAt(i);
    return out;
  }
  function positionsOf(block) {  // uint16 triples on a grid -> Float32Array of metres
    const out = new Float32Array(block.count * 3);
    if (!block.count) return out;
    const b = bytesOf(block.xyz);
    for (let i = 0; i < out.length; ++i)
      out[i] = block.origin[i % 3] + (b[2 * i] | (b[2 * i + 1] << 8)) * block.step_m;
    return out;
  }

  // --- scene ------------------------------------------------------------------------------
  let renderer;
  try {
    // No antialiasing: it halves the frame rate of a software renderer (SwiftShader, llvmpipe)
    // and points gain nothing from it.
    renderer = new THREE.WebGLRenderer({canvas: canvas, antialias: false,
                                        preserveDrawingBuffer: true});
  } catch (e) {  // no WebGL (disabled, or a headless browser without one): say so, draw nothing
    const note = document.createElement('p');
    note.className = 'no-webgl';
    note.textContent = 'This browser could not start WebGL (' + e.message + '): no 3D view. ' +
                       'The rest of the page does not need it.';
    root.replaceChildren(note);
    root.style.height = 'auto';
    return;
  }
  renderer.setPixelRatio(Math.min(2, window.devicePixelRatio || 1));
  renderer.setClearColor(0xf4f5f7, 1);
  const scene = new THREE.Scene();
  const camera = new THREE.PerspectiveCamera(50, 1, 0.01, 500);
  camera.up.set(0, 0, 1);
  const layers = {};
  for (const name of ['map', 'second_map', 'objects', 'boxes', 'surfaces', 'path', 'arrows']) {
    layers[name] = new THREE.Group();
    scene.add(layers[name]);
  }
  const bounds = new THREE.Box3();

  function pointCloud(positions, colors, color, size, dimmable) {
    const g = new THREE.BufferGeometry();
    g.setAttribute('position', new THREE.BufferAttribute(positions, 3));
    if (colors) g.setAttribute('color', new THREE.BufferAttribute(colors, 3, true));
    const m = new THREE.PointsMaterial({size: size, vertexColors: !!colors,
                                        color: colors ? 0xffffff : color, transparent: dimmable});
    return new THREE.Points(g, m);
  }

  if (data.map.count) {
    const pos = positionsOf(data.map);
    layers.map.add(pointCloud(pos, bytesOf(data.map.rgb), 0, data.map.point_size_m, false));
    // The view frames the map's 1st to 99th percentile on each axis (a few stray points far away
    // do not shrink it).
    const n = pos.length / 3, step = Math.max(1, Math.floor(n / 20000)), lo = [], hi = [];
    for (let k = 0; k < 3; ++k) {
      const sample = [];
      for (let i = 0; i < n; i += step) sample.push(pos[3 * i + k]);
      sample.sort(function (a, b) { return a - b; });
      lo.push(sample[Math.floor(0.01 * (sample.length - 1))]);
      hi.push(sample[Math.ceil(0.99 * (sample.length - 1))]);
    }
    bounds.set(new THREE.Vector3(lo[0], lo[1], lo[2]), new THREE.Vector3(hi[0], hi[1], hi[2]));
  }

  // A second map (objmap report --diff: the after run's, registered and tinted) and arrows (a
  // moved object's old place to its new one).
  if (data.second_map && data.second_map.count)
    layers.second_map.add(pointCloud(positionsOf(data.second_map), bytesOf(data.second_map.rgb), 0,
                                     data.second_map.point_size_m, false));
  for (const a of data.arrows || []) {
    const from = new THREE.Vector3(a.from[0], a.from[1], a.from[2]);
    const dir = new THREE.Vector3(a.to[0], a.to[1], a.to[2]).sub(from);
    const length = Math.max(dir.length(), 1e-3);
    const head = Math.min(0.1, 0.3 * length);
    layers.arrows.add(new THREE.ArrowHelper(dir.normalize(), from, length, a.color, head,
                                            0.5 * head));
  }

  const BOX_EDGES = [0, 1, 1, 3, 3, 2, 2, 0, 4, 5, 5, 7, 7, 6, 6, 4, 0, 4, 1, 5, 2, 6, 3, 7];
  function boxMatrix(o) {  // box frame -> world: rotation columns are the box axes
    const r = o.rotation, c = o.center;
    return new THREE.Matrix4().set(r[0], r[1], r[2], c[0], r[3], r[4], r[5], c[1],
                                   r[6], r[7], r[8], c[2], 0, 0, 0, 1);
  }
  const objects = data.objects.map(function (o) {
    const colour = new THREE.Color(o.color);
    let body;
    if (o.mesh) {  // a mesh when the run has one, else the points
      const g = new THREE.BufferGeometry();
      g.setAttribute('position', new THREE.BufferAttribute(positionsOf(o.mesh), 3));
      g.setIndex(o.mesh.triangles);
      g.computeVertexNormals();
      body = new THREE.Mesh(g, new THREE.MeshBasicMaterial({color: colour, transparent: true}));
    } else {
      body = pointCloud(positionsOf(o.points), null, colour, data.map.point_size_m * 1.6, true);
    }
    layers.objects.add(body);
    const corners = [];
    for (let k = 0; k < 8; ++k)
      corners.push((k & 1 ? 1 : -1) * o.half_extent[0], (k & 2 ? 1 : -1) * o.half_extent[1],
                   (k & 4 ? 1 : -1) * o.half_extent[2]);
    const g = new THREE.BufferGeometry();
    g.setAttribute('position', new THREE.BufferAttribute(new Float32Array(corners), 3));
    g.setIndex(BOX_EDGES);
    const box = new THREE.LineSegments(g, new THREE.LineBasicMaterial({color: colour,
                                                                        transparent: true}));
    const matrix = boxMatrix(o);
    box.matrixAutoUpdate = false;
    box.matrix.copy(matrix);
    layers.boxes.add(box);
    const top = new THREE.Vector3(0, 0, 0).applyMatrix4(matrix);
    top.z += Math.abs(o.rotation[6] * o.half_extent[0]) + Math.abs(o.rotation[7] * o.half_extent[1]) +
             Math.abs(o.rotation[8] * o.half_extent[2]);
    const label = document.createElement('div');
    label.className = 'label';
    label.dataset.id = o.id;
    label.style.borderColor = o.color;
    label.textContent = o.label || o.id + ' ' + o.class;
    labelsBox.appendChild(label);
    bounds.expandByPoint(top);
    return {data: o, body: body, box: box, label: label, top: top,
            inverse: matrix.clone().invert()};
  });

  for (const s of data.surfaces) {
    if (s.outline.length < 3) continue;
    const pts = s.outline.map(function (p) { return new THREE.Vector3(p[0], p[1], p[2]); });
    const centre = new THREE.Vector3();
    for (const p of pts) centre.add(p);
    centre.divideScalar(pts.length);
    const fan = [];
    for (let i = 0; i < pts.length; ++i) {
      const a = pts[i], b = pts[(i + 1) % pts.length];
      fan.push(centre.x, centre.y, centre.z, a.x, a.y, a.z, b.x, b.y, b.z);
    }
    const colour = s.label === 'floor' ? 0x8899aa : s.label === 'table' ? 0xc08a40 : 0x9a7fb8;
    const g = new THREE.BufferGeometry();
    g.setAttribute('position', new THREE.BufferAttribute(new Float32Array(fan), 3));
    layers.surfaces.add(new THREE.Mesh(g, new THREE.MeshBasicMaterial({
        color: colour, transparent: true, opacity: 0.22, side: THREE.DoubleSide,
        depthWrite: false})));
    const line = new THREE.BufferGeometry().setFromPoints(pts.concat([pts[0]]));
    layers.surfaces.add(new THREE.Line(line, new THREE.LineBasicMaterial({color: colour})));
  }

  if (data.path.length > 1) {
    const pts = data.path.map(function (p) { return new THREE.Vector3(p[0], p[1], p[2]); });
    layers.path.add(new THREE.Line(new THREE.BufferGeometry().setFromPoints(pts),
                                   new THREE.LineBasicMaterial({color: 0xe60078})));
    if (bounds.isEmpty())
      for (const p of pts) bounds.expandByPoint(p);
  }

  // --- orbit, pan, zoom ------------------------------------------------------------------------
  const target = new THREE.Vector3(), size = new THREE.Vector3();
  if (bounds.isEmpty()) bounds.set(new THREE.Vector3(-1, -1, -1), new THREE.Vector3(1, 1, 1));
  bounds.getCenter(target);
  bounds.getSize(size);
  const view = {azimuth: -Math.PI / 3, elevation: 0.6, distance: 0.8 * Math.max(size.length(), 0.5)};

  function placeCamera() {
    const ce = Math.cos(view.elevation);
    camera.position.set(target.x + view.distance * ce * Math.cos(view.azimuth),
                        target.y + view.distance * ce * Math.sin(view.azimuth),
                        target.z + view.distance * Math.sin(view.elevation));
    camera.lookAt(target);
  }

  let pending = false;
  function redraw() {
    if (pending) return;
    pending = true;
    requestAnimationFrame(draw);
  }
  function resize() {
    const w = root.clientWidth, h = root.clientHeight;
    renderer.setSize(w, h, false);
    camera.aspect = w / Math.max(h, 1);
    camera.updateProjectionMatrix();
  }
  function draw() {
    pending = false;
    resize();
    placeCamera();
    renderer.render(scene, camera);
    const w = root.clientWidth, h = root.clientHeight;
    placeLabels(w, h);
    root.dataset.frames = String(Number(root.dataset.frames || 0) + 1);
  }

  // Labels above their boxes; where they crowd, the nearest (a selected or searched one first)
  // keeps its place and those it would cover are hidden until the view zooms in.
  let selected = null;
  function placeLabels(w, h) {
    const showLabels = root.querySelector('input[data-layer=labels]').checked;
    const v = new THREE.Vector3();
    const shown = [];
    for (const o of objects) {
      v.copy(o.top).project(camera);
      const visible = showLabels && v.z < 1 && Math.abs(v.x) <= 1.05 && Math.abs(v.y) <= 1.05;
      o.label.style.display = visible ? '' : 'none';
      o.x = (v.x + 1) / 2 * w;
      o.y = (1 - v.y) / 2 * h;
      o.depth = v.z;
      o.label.style.left = o.x.toFixed(1) + 'px';
      o.label.style.top = o.y.toFixed(1) + 'px';
      if (visible) shown.push(o);
    }
    const rank = function (o) {
      return o.data.id === selected ? 0 : o.label.classList.contains('hit') ? 1 : 2;
    };
    shown.sort(function (a, b) { return rank(a) - rank(b) || a.depth - b.depth; });
    const placed = [];
    for (const o of shown) {
      const lw = o.label.offsetWidth, lh = o.label.offsetHeight;
      const r = {x0: o.x - lw / 2 - 2, x1: o.x + lw / 2 + 2, y0: o.y - lh - 1, y1: o.y + 1};
      const covered = placed.some(function (p) {
        return r.x0 < p.x1 && p.x0 < r.x1 && r.y0 < p.y1 && p.y0 < r.y1;
      });
      if (covered) o.label.style.display = 'none';
      else placed.push(r);
    }
    root.dataset.labelsHidden = String(shown.length - placed.length);
  }

  // Orbit, pan and zoom from anywhere over the view but its toolbar and panel (a drag may start
  // on a label; a click on a label selects its object, elsewhere the object under the pointer).
  let drag = null;
  const onControls = function (e) { return !!e.target.closest('.toolbar, .panel'); };
  root.addEventListener('contextmenu', function (e) {
    if (!onControls(e)) e.preventDefault();
  });
  root.addEventListener('pointerdown', function (e) {
    if (onControls(e)) return;
    drag = {x: e.clientX, y: e.clientY, pan: e.button === 2 || e.shiftKey, moved: 0,
            label: e.target.classList.contains('label') ? Number(e.target.dataset.id) : null};
    root.setPointerCapture(e.pointerId);
  });
  root.addEventListener('pointermove', function (e) {
    if (!drag) return;
    const dx = e.clientX - drag.x, dy = e.clientY - drag.y;
    drag.x = e.clientX;
    drag.y = e.clientY;
    drag.moved += Math.abs(dx) + Math.abs(dy);
    if (drag.pan) {
      const scale = 2 * view.distance * Math.tan(camera.fov * Math.PI / 360) / root.clientHeight;
      const right = new THREE.Vector3().setFromMatrixColumn(camera.matrix, 0);
      const up = new THREE.Vector3().setFromMatrixColumn(camera.matrix, 1);
      target.addScaledVector(right, -dx * scale).addScaledVector(up, dy * scale);
    } else {
      view.azimuth -= dx * 0.008;
      view.elevation = Math.min(1.55, Math.max(-1.55, view.elevation + dy * 0.008));
    }
    redraw();
  });
  root.addEventListener('pointerup', function (e) {
    const click = drag && drag.moved < 4 ? drag : null;
    drag = null;
    if (click && click.label !== null) select(click.label);  // the pointer is captured: no click
    else if (click) pick(e);
  });
  root.addEventListener('wheel', function (e) {
    if (onControls(e)) return;
    e.preventDefault();
    view.distance = Math.min(400, Math.max(0.05, view.distance * Math.exp(e.deltaY * 0.001)));
    redraw();
  }, {passive: false});
  window.addEventListener('resize', redraw);

  // A click on the canvas: the nearest object whose box the ray enters (slab test in its frame).
  function pick(e) {
    const r = canvas.getBoundingClientRect();
    const ndc = new THREE.Vector2((e.clientX - r.left) / r.width * 2 - 1,
                                  1 - (e.clientY - r.top) / r.height * 2);
    const ray = new THREE.Raycaster();
    ray.setFromCamera(ndc, camera);
    let best = null, bestT = Infinity;
    for (const o of objects) {
      const local = ray.ray.clone().applyMatrix4(o.inverse);
      const he = o.data.half_extent;
      const box = new THREE.Box3(new THREE.Vector3(-he[0], -he[1], -he[2]),
                                 new THREE.Vector3(he[0], he[1], he[2]));
      const hit = local.intersectBox(box, new THREE.Vector3());
      if (!hit) continue;
      const t = hit.distanceTo(local.origin);
      if (t < bestT) {
        bestT = t;
        best = o;
      }
    }
    if (best) {
      select(best.data.id);
    } else {
      panel.classList.remove('open');
      selected = null;
    }
  }

  // --- the object panel ----------------------------------------------------------------------
  function text(tag, content) {
    const el = document.createElement(tag);
    el.textContent = content;
    return el;
  }
  function select(id) {
    const o = objects.find(function (x) { return x.data.id === id; });
    if (!o) return;
    const d = o.data;
    panel.replaceChildren();
    panel.dataset.id = d.id;
    const thumb = document.querySelector('figure.object[data-object-id=' +
                                         JSON.stringify(String(d.id)) + '] img');
    if (thumb) {
      const img = document.createElement('img');
      img.src = thumb.src;
      img.alt = d.id + ' ' + d.class;
      panel.appendChild(img);
    }
    panel.appendChild(text('h3', d.label || d.class + ' (id ' + d.id + ')'));
    const cm = function (m) { return (200 * m).toFixed(0); };
    const lines = [
      'position ' + d.center.map(function (x) { return x.toFixed(3); }).join(', ') + ' m',
      'size ' + cm(d.half_extent[0]) + ' × ' + cm(d.half_extent[1]) + ' × ' +
          cm(d.half_extent[2]) + ' cm',
      d.observations + ' observations' + (d.views ? ', ' + d.views + ' views' : ''),
      'score ' + d.score.toFixed(2) + ', ' + d.points.of + ' points'];
    for (const l of lines) panel.appendChild(text('div', l));
    panel.appendChild(text('div', d.relations.length ? 'relations:' : 'no relations'));
    const ul = document.createElement('ul');
    for (const r of d.relations) ul.appendChild(text('li', r));
    panel.appendChild(ul);
    panel.classList.add('open');
    selected = d.id;
    redraw();
  }

  // --- the search: `objmap query`'s grammar, the matches computed by objmap ----------------------
  const SURFACES = ['floor', 'table', 'seat', 'surface'];
  const known = new Set(data.known_classes);
  function canonical(s) {
    const n = s.toLowerCase().replace(/[_\s]+/g, ' ').trim();
    return Object.prototype.hasOwnProperty.call(data.class_aliases, n) ? data.class_aliases[n] : n;
  }
  function singulars(phrase) {  // as lib/objmap/scene/query.cpp: the last word's singular forms
    const out = [phrase];
    const at = phrase.lastIndexOf(' ');
    const head = at < 0 ? '' : phrase.slice(0, at + 1), w = at < 0 ? phrase : phrase.slice(at + 1);
    const irregular = {mice: 'mouse', people: 'person', knives: 'knife', sheep: 'sheep'};
    if (irregular[w]) out.push(head + irregular[w]);
    const ends = function (s) { return w.length > s.length && w.endsWith(s); };
    if (ends('ies')) out.push(head + w.slice(0, -3) + 'y');
    if (ends('es')) out.push(head + w.slice(0, -2));
    if (ends('s')) out.push(head + w.slice(0, -1));
    return out;
  }
  function resolve(words, surfaceOk) {
    for (const s of singulars(words.join(' '))) {
      if (surfaceOk && SURFACES.indexOf(s) >= 0) return s;
      if (known.has(canonical(s))) return canonical(s);
    }
    return null;
  }
  // "cup on table" -> "cup on table" as objmap spells it, or {error}.
  function parse(textIn) {
    const words = canonical(textIn).split(' ').filter(function (w) {
      return w && w !== 'the' && w !== 'a' && w !== 'an';
    });
    if (!words.length) return null;
    let rel = words.findIndex(function (w) { return /^(on|near|above|under)$/.test(w); });
    if (rel < 0) rel = words.length;
    const subject = resolve(words.slice(0, rel), false);
    if (!subject) return {error: "'" + words.slice(0, rel).join(' ') + "' is not a class"};
    if (rel === words.length) return {key: subject};
    const targetWords = words.slice(rel + 1);
    const t = targetWords.length ? resolve(targetWords, true) : null;
    if (!t) return {error: "'" + targetWords.join(' ') + "' is not a class nor a surface"};
    return {key: subject + ' ' + words[rel] + ' ' + t};
  }
  function highlight() {
    const q = parse(search.value);
    let ids = null;
    if (!q) {
      searchResult.textContent = '';
    } else if (q.error) {
      searchResult.textContent = q.error;
      ids = [];
    } else {
      ids = data.queries[q.key] || [];
      searchResult.textContent = ids.length ? ids.length + ' × ' + q.key + ': ' + ids.join(', ')
                                            : 'no ' + q.key + ' in this map';
    }
    root.dataset.hits = ids ? ids.join(',') : '';
    for (const o of objects) {
      const hit = ids !== null && ids.indexOf(o.data.id) >= 0;
      const dim = ids !== null && !hit;
      o.label.classList.toggle('hit', hit);
      o.label.classList.toggle('dim', dim);
      o.body.material.opacity = dim ? 0.15 : 1;
      o.box.material.opacity = dim ? 0.15 : 1;
      o.box.material.color.set(hit ? 0xffc400 : o.data.color);
    }
    redraw();
  }
  search.addEventListener('input', highlight);

  for (const input of root.querySelectorAll('input[data-layer]')) {
    input.addEventListener('change', function () {
      if (layers[input.dataset.layer]) layers[input.dataset.layer].visible = input.checked;
      redraw();
    });
  }
  root.dataset.ready = '1';
  redraw();
})();

// The sinew-live page: draws the streamed skin, sends the steering (docs/live.md, "Protocol").
import * as THREE from 'three';
import { OrbitControls } from 'three/addons/controls/OrbitControls.js';

const $ = (id) => document.getElementById(id);
const params = new URLSearchParams(location.search);
const token = params.get('token');
// The model's up axis: ?up=y|z in the URL, else what sinew-live was told (--up, in "hello").
let upAxis = params.get('up') === 'y' ? 'y' : 'z';
const ws = new WebSocket(`${location.protocol === 'https:' ? 'wss' : 'ws'}://${location.host}/ws` +
                         (token ? `?token=${encodeURIComponent(token)}` : ''));
ws.binaryType = 'arraybuffer';

// Scene, camera, lights.
const renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
renderer.setPixelRatio(window.devicePixelRatio);
$('view').appendChild(renderer.domElement);
const scene = new THREE.Scene();
scene.background = new THREE.Color(0x30343c);
const camera = new THREE.PerspectiveCamera(35, 1, 1e-4, 100);
scene.add(new THREE.HemisphereLight(0xffffff, 0x404040, 1.6));
const sun = new THREE.DirectionalLight(0xffffff, 1.8);
camera.add(sun);
sun.position.set(0.3, 0.5, 1);
scene.add(camera);
const controls = new OrbitControls(camera, renderer.domElement);

let mesh = null, rest = null, positions = null, colours = null, vertexCount = 0;
let hello = null, steering = false, nextId = 1;
const live = { frames: 0, framesAtLast: 0, lastRate: performance.now(), fps: 0, status: null, step: 0,
               time: 0, lastFrameId: 0, field: 'displacement', min: 0, max: 0, lastErrorAt: -1e9 };
window.sinewLive = live;  // for tests: frames received, last displacements

function send(msg) {
  msg.id = nextId++;
  if (ws.readyState === WebSocket.OPEN) ws.send(JSON.stringify(msg));
  return msg.id;
}
window.sinewSend = send;

function resize() {
  const w = window.innerWidth, h = window.innerHeight;
  renderer.setSize(w, h);
  camera.aspect = w / h;
  camera.updateProjectionMatrix();
}
window.addEventListener('resize', resize);
resize();

// Colour map (viridis, 5 stops) and the colour bar.
const stops = [[0.267, 0.005, 0.329], [0.231, 0.322, 0.545], [0.129, 0.569, 0.549],
               [0.369, 0.788, 0.384], [0.993, 0.906, 0.144]];
function colour(t, out, i) {
  t = Math.min(1, Math.max(0, t)) * (stops.length - 1);
  const k = Math.min(stops.length - 2, Math.floor(t)), f = t - k;
  for (let c = 0; c < 3; ++c) out[i + c] = stops[k][c] * (1 - f) + stops[k + 1][c] * f;
}
(function drawBar() {
  const g = $('bar').getContext('2d'), h = $('bar').height, px = [0, 0, 0];
  for (let y = 0; y < h; ++y) {
    colour(1 - y / (h - 1), px, 0);
    g.fillStyle = `rgb(${px.map((v) => Math.round(v * 255)).join(',')})`;
    g.fillRect(0, y, $('bar').width, 1);
  }
})();
const units = { displacement: ['|u|', 1e3, 'mm'], von_mises: ['von Mises', 1e-3, 'kPa'],
                jacobian: ['J', 1, ''] };

function buildMesh(buf) {
  const h = new Uint32Array(buf, 0, 4);
  vertexCount = h[1];
  const tris = h[2];
  rest = new Float32Array(buf, 16, vertexCount * 3);
  const index = new Uint32Array(buf, 16 + 12 * vertexCount, tris * 3);
  const geometry = new THREE.BufferGeometry();
  positions = new Float32Array(rest);
  colours = new Float32Array(vertexCount * 3).fill(0.7);
  geometry.setAttribute('position', new THREE.BufferAttribute(positions, 3));
  geometry.setAttribute('color', new THREE.BufferAttribute(colours, 3));
  geometry.setIndex(new THREE.BufferAttribute(index, 1));
  geometry.computeVertexNormals();
  geometry.computeBoundingSphere();
  mesh = new THREE.Mesh(geometry, new THREE.MeshStandardMaterial(
      { vertexColors: true, roughness: 0.7, side: THREE.DoubleSide }));
  scene.add(mesh);
  frontView();
}

// The first view faces the model as `sinew-render --view front` does: from +z looking along −z
// with y up, from −y looking along +y with z up (the three-quarter view it had looked at the
// forehead from below).
function frontView() {
  if (!mesh) return;
  const s = mesh.geometry.boundingSphere;
  controls.target.copy(s.center);
  camera.near = s.radius / 100;
  camera.far = s.radius * 100;
  const eye = upAxis === 'y' ? new THREE.Vector3(0, 0, 1) : new THREE.Vector3(0, -1, 0);
  camera.position.copy(s.center).add(eye.multiplyScalar(s.radius * 3));
  camera.up.set(0, upAxis === 'y' ? 1 : 0, upAxis === 'y' ? 0 : 1);
  camera.updateProjectionMatrix();
  controls.update();
}

function applyFrame(buf) {
  const h = new Uint32Array(buf, 0, 4);
  const n = h[1];
  if (!mesh || n !== vertexCount) return;
  const d = new Float64Array(buf, 16, 2);
  const disp = new Float32Array(buf, 32, n * 3), values = new Float32Array(buf, 32 + 12 * n, n);
  for (let i = 0; i < 3 * n; ++i) positions[i] = rest[i] + disp[i];
  let lo = Infinity, hi = -Infinity;
  for (let i = 0; i < n; ++i) { lo = Math.min(lo, values[i]); hi = Math.max(hi, values[i]); }
  const field = ['displacement', 'von_mises', 'jacobian'][h[2]] || 'displacement';
  if (document.activeElement !== $('field')) $('field').value = field;  // e.g. after a refusal
  if (field === 'displacement') lo = 0;
  const span = hi > lo ? hi - lo : 1;
  for (let i = 0; i < n; ++i) colour((values[i] - lo) / span, colours, 3 * i);
  const g = mesh.geometry;
  g.attributes.position.needsUpdate = true;
  g.attributes.color.needsUpdate = true;
  g.computeVertexNormals();
  g.computeBoundingSphere();  // the raycaster's first test: a pick beyond the rest shape would miss
  const [label, scale, unit] = units[field];
  $('bar_max').textContent = `${(hi * scale).toPrecision(3)} ${unit}`;
  $('bar_min').textContent = `${(lo * scale).toPrecision(3)} ${unit}`;
  $('bar_label').textContent = label;
  Object.assign(live, { frames: live.frames + 1, step: d[0], time: d[1], lastFrameId: h[3],
                        field, min: lo, max: hi, displacement: disp });
}

function muscleRow(m) {
  const row = document.createElement('div');
  row.className = 'muscle';
  row.innerHTML = '<span class="name"></span>' +
      '<input type="range" min="0" max="1" step="0.01" value="0"> <span class="v">curve</span> ' +
      '<button>curve</button>';
  const name = row.querySelector('.name');
  name.textContent = name.title = m.name;  // the model's name, as text (never markup)
  const [slider, button] = [row.querySelector('input'), row.querySelector('button')];
  slider.dataset.muscle = m.name;
  slider.addEventListener('input', () => {
    slider.dataset.movedAt = performance.now();
    row.querySelector('.v').textContent = Number(slider.value).toFixed(2);
    send({ type: 'activation', muscle: m.name, value: Number(slider.value) });
  });
  button.addEventListener('click', () => {
    row.querySelector('.v').textContent = 'curve';
    send({ type: 'activation', muscle: m.name, value: null });
  });
  $('muscles').appendChild(row);
}

// Each muscle row shows the engine's override (status.overrides), so a refused value (above what
// the time step was planned for) does not stay on the page; not within a second of moving it (the
// status may predate the move).
function showOverrides(overrides) {
  const now = performance.now();
  for (const slider of document.querySelectorAll('#muscles input')) {
    if (now - Number(slider.dataset.movedAt || -1e9) < 1000 || !(slider.dataset.muscle in overrides)) continue;
    const a = overrides[slider.dataset.muscle];
    slider.parentElement.querySelector('.v').textContent = a === null ? 'curve' : a.toFixed(2);
    if (a !== null) slider.value = a;
  }
}

function showStatus(s) {
  live.status = s;
  showOverrides(s.overrides);
  const now = performance.now();
  if (now - live.lastRate > 1000) {
    live.fps = (live.frames - live.framesAtLast) * 1000 / (now - live.lastRate);
    live.framesAtLast = live.frames;
    live.lastRate = now;
  }
  // In playback the frame shown is the file's, not the engine's (which waits at step 0).
  const where = s.playback
    ? `playback: frame ${s.playback.frame + 1} of ${s.playback.frames}, ` +
      `t = ${hello.playback.times[s.playback.frame].toFixed(5)} s  step ${hello.playback.steps[s.playback.frame]}`
    : `t = ${s.time.toFixed(5)} s  step ${s.step}  ${s.paused ? (s.at_end ? 'end of scene (paused)' : 'paused') : 'running'}`;
  $('status').textContent = where +
      `  ${Math.round(s.steps_per_second)} steps/s  ${s.sim_seconds_per_wall_second.toPrecision(3)} sim s / wall s` +
      `  ${live.fps.toFixed(1)} frames/s` + (hello && hello.warnings.length ? `  warnings: ${hello.warnings.join('; ')}` : '');
  if (!s.playback) {
    $('playback').hidden = true;
    for (const o of $('field').options) o.disabled = false;  // live: every field
  }
  $('recording').textContent = s.recording ? ` recording to ${s.recording}` : '';
  $('record').textContent = s.recording ? 'Stop recording' : 'Record';
  // The engine's message while it stands; a refused message's reply stays for 6 s.
  if (s.error) $('message').textContent = `engine: ${s.error}\n(reset, or lower activations and resume)`;
  else if (performance.now() - live.lastErrorAt > 6000) $('message').textContent = '';
}

ws.addEventListener('message', (ev) => {
  if (ev.data instanceof ArrayBuffer) {
    const tag = new Uint32Array(ev.data, 0, 1)[0];
    if (tag === 1) buildMesh(ev.data);
    else if (tag === 2) applyFrame(ev.data);
    return;
  }
  const m = JSON.parse(ev.data);
  if (m.type === 'hello') {
    hello = m;
    if (!params.has('up') && m.up === 'y') { upAxis = 'y'; frontView(); }
    $('title').textContent = m.title || m.scene;
    m.muscles.forEach(muscleRow);
    if (m.playback) {
      $('playback').hidden = false;
      $('frame').max = m.playback.times.length - 1;
      $('frame_time').textContent = `t = ${m.playback.times[0].toFixed(4)} s`;
      for (const o of $('field').options) {  // the element fields the file stores
        o.disabled = !m.playback.fields.includes(o.value);
        if (o.disabled) o.title = 'not in the results file (the scene\'s output.fields)';
      }
    }
    if (!m.drag) {  // the server says why (no effect 'loads', or a backend without force slots)
      $('drag_refusal').textContent = `No dragging here: ${m.drag_refusal}.`;
      $('drag_refusal').hidden = false;
      $('radius').disabled = $('stiffness').disabled = true;
    }
    $('radius').value = (m.drag_radius * 1e3).toFixed(1);
    $('radius_value').textContent = ` ${$('radius').value}`;
  } else if (m.type === 'role') {
    steering = m.steering;
    $('role').textContent = steering ? 'You steer this session.' : 'Watching (another client steers).';
  } else if (m.type === 'status') {
    showStatus(m);
  } else if (m.type === 'error') {
    $('message').textContent = `error: ${m.message}`;
    live.lastError = m.message;
    live.lastErrorAt = performance.now();
  }
});
ws.addEventListener('close', () => { $('status').textContent = 'disconnected'; });

$('pause').onclick = () => send({ type: 'pause' });
$('resume').onclick = () => send({ type: 'resume' });
$('step').onclick = () => send({ type: 'step', count: 1 });
$('reset').onclick = () => send({ type: 'reset' });
$('record').onclick = () => send({ type: 'record', on: !(live.status && live.status.recording) });
$('field').onchange = () => send({ type: 'field', field: $('field').value });
$('frame').addEventListener('input', () => {
  $('frame_time').textContent = `t = ${hello.playback.times[Number($('frame').value)].toFixed(4)} s`;
  send({ type: 'seek', frame: Number($('frame').value) });
});
$('continue').onclick = () => send({ type: 'continue' });
for (const id of ['radius', 'stiffness'])
  $(id).addEventListener('input', () => { $(`${id}_value`).textContent = ` ${$(id).value}`; });
$('stiffness_value').textContent = ` ${$('stiffness').value}`;

// Click-drag on the skin: a spring from the picked point to the mouse (on the plane through the
// point facing the camera) pulls the nodes within the radius; the ring shows the radius.
const raycaster = new THREE.Raycaster(), pointer = new THREE.Vector2();
const ring = new THREE.Mesh(new THREE.RingGeometry(0.95, 1, 48),
                            new THREE.MeshBasicMaterial({ color: 0xffaa00, side: THREE.DoubleSide }));
ring.visible = false;
scene.add(ring);
let drag = null, lastDragSent = 0, trailingDrag = 0;
function pick(ev) {
  const r = renderer.domElement.getBoundingClientRect();
  pointer.set(((ev.clientX - r.left) / r.width) * 2 - 1, -((ev.clientY - r.top) / r.height) * 2 + 1);
  raycaster.setFromCamera(pointer, camera);
}
function dragForce() {
  const k = Number($('stiffness').value);
  const f = drag.target.clone().sub(drag.point).multiplyScalar(k);
  const max = 100;
  if (f.length() > max) f.setLength(max);
  return f;
}
function sendDrag(force) {
  send({ type: 'drag', point: drag.point.toArray(), force: force.toArray(),
         radius: Number($('radius').value) * 1e-3 });
}
renderer.domElement.addEventListener('pointerdown', (ev) => {
  if (!mesh || ev.button !== 0 || !steering || !hello.drag) return;
  pick(ev);
  const hit = raycaster.intersectObject(mesh)[0];
  if (!hit) return;
  controls.enabled = false;
  const normal = camera.getWorldDirection(new THREE.Vector3()).negate();
  drag = { point: hit.point.clone(), target: hit.point.clone(),
           plane: new THREE.Plane().setFromNormalAndCoplanarPoint(normal, hit.point) };
  ring.position.copy(hit.point);
  ring.lookAt(hit.point.clone().add(normal));
  ring.scale.setScalar(Number($('radius').value) * 1e-3);
  ring.visible = true;
  sendDrag(new THREE.Vector3());
});
renderer.domElement.addEventListener('pointermove', (ev) => {
  if (!drag) return;
  pick(ev);
  raycaster.ray.intersectPlane(drag.plane, drag.target);
  // At most one drag message per 50 ms, and the last position always sent (a trailing send), so
  // the force matches where the mouse came to rest.
  clearTimeout(trailingDrag);
  const wait = 50 - (performance.now() - lastDragSent);
  const sendNow = () => { if (drag) { sendDrag(dragForce()); lastDragSent = performance.now(); } };
  if (wait <= 0) sendNow(); else trailingDrag = setTimeout(sendNow, wait);
});
window.addEventListener('pointerup', () => {
  if (!drag) return;
  clearTimeout(trailingDrag);
  send({ type: 'release' });
  drag = null;
  ring.visible = false;
  controls.enabled = true;
});

// Where a point (m) appears on the page, in client pixels (the headless-browser test drags there).
live.screenOf = (x, y, z) => {
  const v = new THREE.Vector3(x, y, z).project(camera), r = renderer.domElement.getBoundingClientRect();
  return [r.left + (v.x + 1) / 2 * r.width, r.top + (1 - v.y) / 2 * r.height];
};
live.rest = () => rest;

renderer.setAnimationLoop(() => { controls.update(); renderer.render(scene, camera); });

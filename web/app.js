// SPDX-License-Identifier: MIT
// The page of `harap view`: draws the mesh the server sends, drags its handles with a gizmo and
// shows the server's solves. Protocol: docs/view.md (JSON text to the server; binary frames of
// float32 positions and JSON text back).
import * as THREE from 'three';
import { OrbitControls } from 'three/addons/controls/OrbitControls.js';
import { TransformControls } from 'three/addons/controls/TransformControls.js';
import { OBJExporter } from 'three/addons/exporters/OBJExporter.js';
import { PLYExporter } from 'three/addons/exporters/PLYExporter.js';
import GUI from 'lil-gui';
import uPlot from 'uplot';

const kMeshFrame = 1;
const kPositionsFrame = 2;
const kClustersFrame = 3;
const kFreeGrey = 190 / 255;
const kLevelColors = ['#1f77b4', '#d62728', '#2ca02c', '#ff7f0e', '#9467bd', '#17becf'];

const statusElement = document.getElementById('status');
const energyElement = document.getElementById('energy');
const solveInfoElement = document.getElementById('solve-info');
const editInfoElement = document.getElementById('edit-info');
const errorsElement = document.getElementById('errors');
function showError(text) {
  errorsElement.insertAdjacentHTML('afterbegin', '<li></li>');
  errorsElement.firstChild.textContent = text;
}

// What the page shows and what a test or a benchmark reads (window.harapView).
const state = {
  ready: false, mesh: null, groups: [], energy: null, lastSolve: null, framesDrawn: 0,
  stoppedSolves: 0,
  errors: [], timings: { preview: [], full: [], edit: [], previewSolve: [], editServer: [], render: [],
    frame: [], previewQueued: [], previewAnswered: [], previewDrawn: [] },
  scenarioToml: null,
};
window.harapView = state;

// Renderer, camera, lights.
const viewport = document.getElementById('viewport');
// Multisampling costs a software renderer (SwiftShader, llvmpipe: a machine without a GPU) more
// than the whole draw otherwise; a GPU does it for free.
function softwareRenderer() {
  const gl = document.createElement('canvas').getContext('webgl2');
  const info = gl?.getExtension('WEBGL_debug_renderer_info');
  const name = info ? gl.getParameter(info.UNMASKED_RENDERER_WEBGL) : '';
  return /swiftshader|llvmpipe|software/i.test(name);
}
const software = softwareRenderer();
state.softwareRenderer = software;
const renderer = new THREE.WebGLRenderer({ antialias: !software,
  preserveDrawingBuffer: true });
renderer.setPixelRatio(window.devicePixelRatio);
renderer.setSize(window.innerWidth, window.innerHeight);
viewport.appendChild(renderer.domElement);
const scene = new THREE.Scene();
scene.background = new THREE.Color(0xf4f4f2);
const camera = new THREE.PerspectiveCamera(40, window.innerWidth / window.innerHeight, 0.001, 1000);
scene.add(new THREE.HemisphereLight(0xffffff, 0x667788, 1.6));
const light = new THREE.DirectionalLight(0xffffff, 1.6);
camera.add(light);
light.position.set(0.5, 1, 1);
scene.add(camera);
let orbit = null;  // made with the mesh, once the up axis is known
const gizmo = new TransformControls(camera, renderer.domElement);
scene.add(gizmo.getHelper());
const pivot = new THREE.Object3D();
scene.add(pivot);
// A software renderer pays for every pixel on the server's cores: while a handle or the view is
// dragged it draws at kSoftwareDragPixelRatio of the resolution, and at full resolution again
// once the drag ends (docs/view.md, large meshes).
const kSoftwareDragPixelRatio = 0.5;
let lowResolution = false;
function setDragResolution(dragging) {
  if (!software || lowResolution === dragging) return;
  lowResolution = dragging;
  renderer.setPixelRatio(dragging ? kSoftwareDragPixelRatio : window.devicePixelRatio);
  requestRender();
}
// For a test: frames drawn at the lowered resolution, and the resolution now.
state.lowResolutionFrames = 0;
state.pixelRatio = () => renderer.getPixelRatio();
gizmo.addEventListener('dragging-changed', (event) => {
  if (orbit) orbit.enabled = !event.value;
  setDragResolution(event.value);
  if (!event.value) moveReleased();
});
gizmo.addEventListener('objectChange', () => moveChanged());
gizmo.addEventListener('change', () => requestRender());

let geometry = null, surface = null, ghost = null, wireframe = null;
let restPositions = null, diagonal = 1;
let meshVertexOf = null, displayVertexOf = null;  // display vertex <-> mesh vertex

const settings = {
  shading: 'smooth', level: 0, wireframe: false, ghost: true, previewOnly: false, gizmoMode: 'translate',
  handle: '', addHandle: false, handleRadius: 0.03,
  optimizer: 'hierarchical', energy: '', solver: '', preset: '', tolerance: 1e-6,
};
const gui = new GUI({ title: 'harap view' });
const display = gui.addFolder('Display');
display.add(settings, 'shading', ['smooth', 'flat']).onChange(updateMaterial);
display.add(settings, 'wireframe').onChange(updateMaterial);
display.add(settings, 'ghost').name('rest pose ghost').onChange(updateMaterial);
let levelController = display.add(settings, 'level', 0, 0, 1).name('hierarchy level')
  .onChange(showLevel);
const handlesFolder = gui.addFolder('Handles');
let handleController = handlesFolder.add(settings, 'handle', ['']).onChange(selectHandle);
handlesFolder.add(settings, 'gizmoMode', ['translate', 'rotate']).name('gizmo')
  .onChange((mode) => gizmo.setMode(mode));
handlesFolder.add(settings, 'previewOnly').name('preview only (key p)');
handlesFolder.add(settings, 'addHandle').name('click adds handle');
handlesFolder.add(settings, 'handleRadius', 0, 0.2, 0.005).name('new handle radius');
handlesFolder.add({ remove: () => removeSelectedHandle() }, 'remove').name('remove handle');
const solveFolder = gui.addFolder('Solve');
const optimizerController = solveFolder.add(settings, 'optimizer', ['classic', 'hierarchical']);
let energyController = solveFolder.add(settings, 'energy', ['']);
let solverController = solveFolder.add(settings, 'solver', ['']);
let presetController = solveFolder.add(settings, 'preset', ['']);
solveFolder.add(settings, 'tolerance', 1e-12, 1e-2);
solveFolder.add({ apply: () => configure() }, 'apply').name('set up with these');
solveFolder.add({ solve: () => send({ type: 'solve' }) }, 'solve').name('full solve');
const downloads = gui.addFolder('Download');
downloads.add({ obj: () => downloadMesh('obj') }, 'obj').name('deformed mesh (OBJ)');
downloads.add({ ply: () => downloadMesh('ply') }, 'ply').name('deformed mesh (PLY)');
downloads.add({ toml: () => send({ type: 'scenario' }) }, 'toml').name('scenario (TOML)');
downloads.add({ png: () => downloadScreenshot() }, 'png').name('screenshot (PNG)');

// Energy-vs-time of the last full solve, one series per hierarchy level.
let plot = null;
function showTrace(trace) {
  const levels = [...new Set(trace.map((entry) => entry[2]))].sort((a, b) => b - a);
  const xs = trace.map((entry) => entry[0]);
  const data = [xs, ...levels.map((level) => trace.map((e) => (e[2] === level ? e[1] : null)))];
  const series = [{ label: 's' }, ...levels.map((level) => ({
    label: `level ${level}`, stroke: kLevelColors[level % kLevelColors.length], spanGaps: false,
    points: { show: true, size: 4 } }))];
  if (plot) plot.destroy();
  plot = new uPlot({ width: 420, height: 160, series, scales: { x: { time: false } },
    axes: [{ label: 'seconds' }, { label: 'energy', size: 70 }] }, data,
    document.getElementById('plot'));
}

// How many vertices the page draws. A software renderer draws a frame of a large mesh in hundreds
// of milliseconds on the cores the server solves on, so there the page asks the server for a
// display of kSoftwareDisplayVertices (docs/view.md, large meshes); the page's address can ask
// for another count (`?display=50000`) or for the server's own budget (`?display=all`).
const kSoftwareDisplayVertices = 20000;
// The server's range (view/protocol.h, ParsePageQuery): outside it the server would refuse the
// connection, and a page cannot read why.
const kMinDisplayVertices = 100;
const kMaxDisplayVertices = 2147483647;
function displayRequest() {
  const asked = new URLSearchParams(location.search).get('display');
  if (asked === 'all') return null;
  if (asked !== null) {
    if (/^[0-9]{1,10}$/.test(asked) && Number(asked) >= kMinDisplayVertices &&
        Number(asked) <= kMaxDisplayVertices) return Number(asked);
    showError(`the page's address: display=${asked} is neither 'all' nor a vertex count in ` +
      `[${kMinDisplayVertices}, ${kMaxDisplayVertices}]; the default applies`);
  }
  return software ? kSoftwareDisplayVertices : null;
}
const displayVertices = displayRequest();
state.displayRequested = displayVertices;
// The WebSocket to this page's own session.
const socket = new WebSocket(`ws://${location.host}/ws` +
  (displayVertices === null ? '' : `?display_vertices=${displayVertices}`));
socket.binaryType = 'arraybuffer';
let nextId = 1;
const sentAt = new Map();  // id -> {kind, time}
function send(message) {
  message.id = nextId++;
  sentAt.set(message.id, { kind: message.type, time: performance.now() });
  socket.send(JSON.stringify(message));
  return message.id;
}
state.sendRaw = (data) => socket.send(data);
socket.onclose = () => { statusElement.textContent = 'disconnected'; };
socket.onmessage = (event) => {
  if (event.data instanceof ArrayBuffer) receiveFrame(event.data);
  else receiveMessage(JSON.parse(event.data));
};

function receiveFrame(buffer) {
  const header = new Uint32Array(buffer, 0, 3);
  if (header[0] === kMeshFrame) {
    // The display: a subset of the mesh's vertices (all of a small mesh's surface).
    const [, vertices, triangles, meshVertices] = new Uint32Array(buffer, 0, 4);
    restPositions = new Float32Array(buffer, 16, 3 * vertices).slice();
    const index = new Uint32Array(buffer, 16 + 12 * vertices, 3 * triangles);
    meshVertexOf = new Uint32Array(buffer, 16 + 12 * (vertices + triangles), vertices).slice();
    displayVertexOf = new Int32Array(meshVertices).fill(-1);
    meshVertexOf.forEach((v, d) => { displayVertexOf[v] = d; });
    buildMesh(restPositions, index);
  } else if (header[0] === kPositionsFrame) {
    const frameStart = performance.now();
    const [, id, count] = header;
    const positions = geometry.attributes.position.array;
    const vertices = positions.length / 3;
    if (count === vertices) {
      positions.set(new Float32Array(buffer, 12, 3 * count));
    } else {
      const indices = new Uint32Array(buffer, 12, count);
      const values = new Float32Array(buffer, 12 + 4 * count, 3 * count);
      for (let i = 0; i < count; ++i) {
        const v = indices[i];
        positions[3 * v] = values[3 * i];
        positions[3 * v + 1] = values[3 * i + 1];
        positions[3 * v + 2] = values[3 * i + 2];
      }
    }
    geometry.attributes.position.needsUpdate = true;
    geometry.computeVertexNormals();
    if (wireframe) wireframe.geometry.attributes.position.needsUpdate = true;
    state.pendingFrameId = id;
    state.timings.frame.push(performance.now() - frameStart);
  } else if (header[0] === kClustersFrame) {
    const [, level, count] = header;
    clustersOfLevel.set(level, new Uint32Array(buffer, 12, count).slice());
    if (level === settings.level) showLevel();
  }
}

function receiveMessage(message) {
  const sent = message.id !== undefined ? sentAt.get(message.id) : undefined;
  switch (message.type) {
    case 'mesh':
      state.mesh = message;
      statusElement.textContent = `${message.vertices} vertices, ${message.elements} ` +
        `${message.tetrahedral ? 'tetrahedra' : 'triangles'}`;
      setChoices(message.choices);
      break;
    case 'status':
      statusElement.textContent = message.stage;
      break;
    case 'ready':
      state.ready = true;
      state.session = message;
      statusElement.textContent = `${state.mesh.vertices} vertices` +
        (state.mesh.display_vertices < state.mesh.vertices
          ? ` (${state.mesh.display_vertices} drawn)` : '') + ` · ${message.optimizer}, ` +
        `${message.energy}, ${message.solver}, ${message.levels} level(s) · set up in ` +
        `${message.setup.seconds.toFixed(2)} s`;
      settings.optimizer = message.optimizer;
      clustersOfLevel.clear();
      levelController = levelController.max(message.levels - 1);
      if (settings.level > message.levels - 1) settings.level = 0;
      showLevel();
      settings.energy = message.energy;
      settings.solver = message.solver;
      gui.controllersRecursive().forEach((c) => c.updateDisplay());
      break;
    case 'handles':
      setGroups(message.groups);
      if (sent && (sent.kind === 'add_handle' || sent.kind === 'remove_handle'))
        afterNextDraw(() => state.timings.edit.push(performance.now() - sent.time));
      break;
    case 'edit': {
      const routes = message.edits.flatMap((e) => e.levels.map((l) => `${l.level}:${l.route}`));
      editInfoElement.textContent = `handle edit ${(1000 * message.seconds).toFixed(0)} ms` +
        (routes.length ? ` (routes ${routes.join(', ')})` : '');
      state.lastEdit = message;
      state.timings.editServer.push(1000 * message.seconds);
      break;
    }
    case 'solved': {
      // A stopped solve is not timed, nor its resumption should the server resume it.
      if (message.interrupted && message.id !== undefined) sentAt.delete(message.id);
      const receivedAt = performance.now();
      const preview = previewAnswered(message.id);
      const eventTime = preview ? preview.eventTime : null;
      afterNextDraw(() => {
        // Where a preview's time went: waiting for the one in flight, the server's answer (its
        // solve and the page's handling of the positions frame, which comes first, included),
        // and the drawing; all from one clock reading per step.
        const drawnAt = performance.now();
        if (eventTime !== null) {
          state.timings.previewQueued.push(preview.sentAt - eventTime);
          state.timings.previewAnswered.push(receivedAt - preview.sentAt);
          state.timings.previewDrawn.push(drawnAt - receivedAt);
        }
        solved(message, sent, eventTime, drawnAt);
      });
      break;
    }
    case 'scenario':
      state.scenarioToml = message.toml;
      download(new Blob([message.toml], { type: 'text/plain' }), 'scenario.toml');
      break;
    case 'error':
      state.errors.push(message);
      showError(message.message);
      previewAnswered(message.id);
      break;
    default:
      break;
  }
  if (message.type === 'scenario' || message.type === 'error') sentAt.delete(message.id);
}

// Drawing on demand: a frame is rendered only when something changed. In software WebGL
// (SwiftShader, a remote machine without a GPU) a continuous render loop would take the CPU
// the solves need.
let renderRequested = false;
let drawnCallbacks = [];
function requestRender() {
  if (renderRequested) return;
  renderRequested = true;
  requestAnimationFrame(() => {
    renderRequested = false;
    const start = performance.now();
    renderer.render(scene, camera);
    state.timings.render.push(performance.now() - start);
    if (lowResolution) state.lowResolutionFrames += 1;
    // The frame rendered here is on the screen when the next animation frame starts.
    const callbacks = drawnCallbacks;
    drawnCallbacks = [];
    if (callbacks.length) requestAnimationFrame(() => callbacks.forEach((callback) => callback()));
  });
}

// Runs `callback` once the frame with the newest positions is on the screen.
let pendingDrawCallbacks = 0;
function afterNextDraw(callback) {
  pendingDrawCallbacks += 1;
  drawnCallbacks.push(() => {
    pendingDrawCallbacks -= 1;
    callback();
  });
  requestRender();
}

// `eventTime`: when the drag event this preview answers happened (null: not a preview).
// `drawnAt`: when its frame was on the screen.
function solved(message, sent, eventTime, drawnAt) {
  state.framesDrawn += 1;
  if (message.interrupted) {
    // A newer move, solve, configure or removal stopped it and solves anew (the server resumes
    // it only if that message is refused, and then it is not timed).
    solveInfoElement.textContent = `full solve stopped after ${(1000 * message.seconds).toFixed(0)} ms ` +
      `(${message.total_iterations} iterations): superseded by a newer request`;
    state.stoppedSolves += 1;
    return;
  }
  state.lastSolve = message;
  if (message.mode === 'full') {
    state.energy = message.energy;
    energyElement.textContent = message.energy === null ? '–' : message.energy.toPrecision(10);
    showTrace(message.trace);
    if (sent) state.timings.full.push(drawnAt - sent.time);
  } else if (eventTime !== null) {
    state.timings.preview.push(drawnAt - eventTime);
    state.timings.previewSolve.push(1000 * message.seconds);
  }
  solveInfoElement.textContent = `${message.mode} ${(1000 * message.seconds).toFixed(0)} ms, ` +
    `${message.total_iterations} iterations`;
  if (message.id !== undefined) sentAt.delete(message.id);
}

function setChoices(choices) {
  energyController = energyController.options(['', ...choices.energies]);
  solverController = solverController.options(['', ...choices.solvers]);
  presetController = presetController.options(choices.presets);
  optimizerController.options(choices.optimizers);
}

function buildMesh(positions, index) {
  geometry = new THREE.BufferGeometry();
  geometry.setAttribute('position', new THREE.BufferAttribute(positions.slice(), 3));
  geometry.setIndex(new THREE.BufferAttribute(index.slice(), 1));
  const colors = new Float32Array(positions.length).fill(kFreeGrey);
  geometry.setAttribute('color', new THREE.BufferAttribute(colors, 3));
  geometry.computeVertexNormals();
  geometry.computeBoundingSphere();
  surface = new THREE.Mesh(geometry, new THREE.MeshStandardMaterial({
    vertexColors: true, roughness: 0.8, side: THREE.DoubleSide }));
  // Frames do not recompute the bounding sphere (a pass over every vertex): never culled.
  surface.frustumCulled = false;
  scene.add(surface);
  const restGeometry = new THREE.BufferGeometry();
  restGeometry.setAttribute('position', new THREE.BufferAttribute(positions, 3));
  restGeometry.setIndex(new THREE.BufferAttribute(index, 1));
  ghost = new THREE.Mesh(restGeometry, new THREE.MeshBasicMaterial({
    color: 0x8899aa, transparent: true, opacity: 0.15, depthWrite: false }));
  scene.add(ghost);
  wireframe = new THREE.Mesh(geometry, new THREE.MeshBasicMaterial({
    color: 0x222222, wireframe: true, transparent: true, opacity: 0.25 }));
  wireframe.frustumCulled = false;
  scene.add(wireframe);
  const sphere = geometry.boundingSphere;
  geometry.computeBoundingBox();
  const extent = geometry.boundingBox.getSize(new THREE.Vector3());
  diagonal = extent.length();
  // Up is the mesh's longest axis (a standing figure, a bar); the camera looks from the front.
  const up = extent.z >= extent.x && extent.z >= extent.y ? new THREE.Vector3(0, 0, 1)
    : extent.y >= extent.x ? new THREE.Vector3(0, 1, 0) : new THREE.Vector3(1, 0, 0);
  const side = Math.abs(up.z) === 1 ? new THREE.Vector3(0.7, -1, 0.25)
    : Math.abs(up.y) === 1 ? new THREE.Vector3(0.7, 0.25, 1) : new THREE.Vector3(0.25, -1, 0.7);
  camera.up.copy(up);
  camera.position.copy(sphere.center).add(side.normalize().multiplyScalar(3.6 * sphere.radius));
  orbit = new OrbitControls(camera, renderer.domElement);
  // OrbitControls starts and ends on every click and wheel step: the resolution drops only once
  // the view moves.
  let orbiting = false;
  orbit.addEventListener('start', () => { orbiting = true; });
  orbit.addEventListener('change', () => {
    if (orbiting) setDragResolution(true);
    requestRender();
  });
  orbit.addEventListener('end', () => {
    orbiting = false;
    setDragResolution(false);
  });
  orbit.target.copy(sphere.center);
  camera.near = sphere.radius / 100;
  camera.far = sphere.radius * 100;
  camera.updateProjectionMatrix();
  orbit.update();
  gizmo.setSize(0.8);
  updateMaterial();
}

function updateMaterial() {
  if (!surface) return;
  surface.material.flatShading = settings.shading === 'flat';
  surface.material.needsUpdate = true;
  wireframe.visible = settings.wireframe;
  ghost.visible = settings.ghost;
  requestRender();
}

// The hierarchy level slider: level 0 shows the handles' colours; a coarser level colours each
// of its clusters (the display vertices that map to one of its vertices), asked for once.
const clustersOfLevel = new Map();
function showLevel() {
  if (!geometry) return;
  if (settings.level === 0) {
    setGroups(state.groups);
    return;
  }
  const clusters = clustersOfLevel.get(settings.level);
  if (!clusters) {
    send({ type: 'level', level: settings.level });
    return;
  }
  const colors = geometry.attributes.color.array;
  const color = new THREE.Color();
  for (let v = 0; v < clusters.length; ++v) {
    const c = clusters[v];
    if (c === 0xffffffff) color.setRGB(kFreeGrey, kFreeGrey, kFreeGrey);
    else color.setHSL(((c * 0.6180339887) % 1 + 1) % 1, 0.65, 0.5 + 0.15 * ((c >> 3) % 2));
    colors[3 * v] = color.r;
    colors[3 * v + 1] = color.g;
    colors[3 * v + 2] = color.b;
  }
  geometry.attributes.color.needsUpdate = true;
  state.levelShown = settings.level;
  requestRender();
}

// Handle groups: colours on the mesh (level 0 of the slider), the gizmo on the selected one.
function setGroups(groups) {
  state.groups = groups;
  if (settings.level !== 0) {
    showLevel();
    selectGroupControls(groups);
    return;
  }
  state.levelShown = 0;
  const colors = geometry.attributes.color.array;
  colors.fill(kFreeGrey);
  const colored = new Uint8Array(colors.length / 3);
  groups.forEach((group) => {
    for (const meshVertex of group.vertices) {
      const v = displayVertexOf[meshVertex];
      if (v < 0 || colored[v]) continue;
      colored[v] = 1;
      colors.set(group.color.map((c) => c / 255), 3 * v);
    }
  });
  geometry.attributes.color.needsUpdate = true;
  requestRender();
  selectGroupControls(groups);
}
function selectGroupControls(groups) {
  const names = groups.map((g, i) => `${i}: ${g.name}`);
  handleController = handleController.options(names);
  if (!names.includes(settings.handle)) settings.handle = names[names.length - 1] ?? '';
  handleController.setValue(settings.handle);
  selectHandle();
}

let selectedGroup = -1;
function selectHandle() {
  selectedGroup = state.groups.findIndex((g, i) => `${i}: ${g.name}` === settings.handle);
  if (selectedGroup < 0) {
    gizmo.detach();
    requestRender();
    return;
  }
  const group = state.groups[selectedGroup];
  const r = group.rotation;
  const rotation = new THREE.Matrix4().set(r[0], r[1], r[2], 0, r[3], r[4], r[5], 0,
    r[6], r[7], r[8], 0, 0, 0, 0, 1);
  const center = new THREE.Vector3(...group.center);
  pivot.quaternion.setFromRotationMatrix(rotation);
  pivot.position.copy(center).applyQuaternion(pivot.quaternion)
    .add(new THREE.Vector3(...group.translation));
  pivot.updateMatrixWorld();
  gizmo.attach(pivot);
  requestRender();
}

// The selected group's transform: rotation R = the pivot's, t = pivot position − R · centre.
function groupTransform() {
  const group = state.groups[selectedGroup];
  const m = new THREE.Matrix3().setFromMatrix4(new THREE.Matrix4().makeRotationFromQuaternion(
    pivot.quaternion));
  const e = m.elements;  // column-major
  const t = pivot.position.clone().sub(new THREE.Vector3(...group.center)
    .applyQuaternion(pivot.quaternion));
  return [e[0], e[3], e[6], t.x, e[1], e[4], e[7], t.y, e[2], e[5], e[8], t.z];
}

// Preview frames: one in flight at a time; newer drag events wait and go with the next one.
let previewInFlight = null, previewPending = false, previewSentTime = null;
let dragEventTime = null, previewEventTime = null;
function moveChanged() {
  if (selectedGroup < 0) return;
  const group = state.groups[selectedGroup];
  const transform = groupTransform();
  group.rotation = [transform[0], transform[1], transform[2], transform[4], transform[5],
    transform[6], transform[8], transform[9], transform[10]];
  group.translation = [transform[3], transform[7], transform[11]];
  if (!previewPending) dragEventTime = performance.now();
  previewPending = true;
  if (previewInFlight === null) sendPreview();
}
// An answer (solve or error) to message `id`: if it is the preview in flight, the next one goes
// out now, so that the server solves it while this one is drawn. Returns when the answered
// preview's drag event happened and when the preview was sent (null if `id` is not the preview
// in flight).
function previewAnswered(id) {
  if (id === undefined || id !== previewInFlight) return null;
  previewInFlight = null;
  const answered = { eventTime: previewEventTime, sentAt: previewSentTime };
  if (previewPending) sendPreview();
  return answered;
}
function sendPreview() {
  previewPending = false;
  previewEventTime = dragEventTime;
  previewSentTime = performance.now();
  previewInFlight = send({ type: 'move', group: selectedGroup, transform: groupTransform(),
    solve: 'preview' });
}
function moveReleased() {
  if (selectedGroup < 0 || settings.previewOnly) return;
  previewPending = false;
  state.releaseId = send({ type: 'move', group: selectedGroup, transform: groupTransform(),
    solve: 'full' });
}
window.addEventListener('keydown', (event) => {
  if (event.key === 'p') {
    settings.previewOnly = !settings.previewOnly;
    gui.controllersRecursive().forEach((c) => c.updateDisplay());
  }
});

// Adding a handle: a click on the mesh picks the nearest vertex of the hit triangle.
const raycaster = new THREE.Raycaster();
renderer.domElement.addEventListener('click', (event) => {
  if (!settings.addHandle || !surface) return;
  const rect = renderer.domElement.getBoundingClientRect();
  const pointer = new THREE.Vector2(((event.clientX - rect.left) / rect.width) * 2 - 1,
    -((event.clientY - rect.top) / rect.height) * 2 + 1);
  raycaster.setFromCamera(pointer, camera);
  geometry.computeBoundingSphere();
  const hit = raycaster.intersectObject(surface)[0];
  if (!hit) return;
  const position = geometry.attributes.position;
  let best = hit.face.a, bestDistance = Infinity;
  for (const v of [hit.face.a, hit.face.b, hit.face.c]) {
    const d = new THREE.Vector3().fromBufferAttribute(position, v).distanceTo(hit.point);
    if (d < bestDistance) { best = v; bestDistance = d; }
  }
  addHandle(best);
});
// `vertex`: a display vertex.
function addHandle(vertex) {
  return send({ type: 'add_handle', vertex: meshVertexOf[vertex],
    radius: settings.handleRadius * diagonal });
}
function removeSelectedHandle() {
  if (selectedGroup >= 0) send({ type: 'remove_handle', group: selectedGroup });
}
state.addHandle = addHandle;
state.setLevel = (level) => {
  settings.level = level;
  levelController.updateDisplay();
  showLevel();
};
// The number of distinct clusters the shown level colours (level 0: every display vertex).
state.clusterCount = () => (settings.level === 0 ? meshVertexOf.length
  : new Set(clustersOfLevel.get(settings.level) ?? []).size);
state.removeHandle = (group) => send({ type: 'remove_handle', group });
// Whether a preview is on its way, or any answer (a preview's included) waits to be drawn and
// timed.
state.previewBusy = () => previewInFlight !== null || pendingDrawCallbacks > 0;
state.requestScenario = () => send({ type: 'scenario' });

function configure() {
  send({ type: 'configure', optimizer: settings.optimizer, energy: settings.energy,
    solver: settings.solver, preset: settings.preset, tolerance: settings.tolerance });
}

// Where the gizmo's centre is on the screen (CSS pixels), for tests that drag it.
state.gizmoScreenPosition = () => {
  const p = pivot.position.clone().project(camera);
  const rect = renderer.domElement.getBoundingClientRect();
  return { x: rect.left + (p.x + 1) / 2 * rect.width, y: rect.top + (1 - p.y) / 2 * rect.height };
};
state.positions = () => Array.from(geometry.attributes.position.array);

function download(blob, name) {
  const link = document.createElement('a');
  link.href = URL.createObjectURL(blob);
  link.download = name;
  link.click();
  setTimeout(() => URL.revokeObjectURL(link.href), 1000);
}
function downloadMesh(format) {
  const exported = new THREE.Mesh(geometry.clone().deleteAttribute('color'));
  if (format === 'obj') {
    download(new Blob([new OBJExporter().parse(exported)], { type: 'text/plain' }), 'deformed.obj');
  } else {
    new PLYExporter().parse(exported, (ply) => download(new Blob([ply]), 'deformed.ply'),
      { binary: true });
  }
}
function downloadScreenshot() {
  renderer.render(scene, camera);
  renderer.domElement.toBlob((blob) => download(blob, 'harap-view.png'));
}

window.addEventListener('resize', () => {
  camera.aspect = window.innerWidth / window.innerHeight;
  camera.updateProjectionMatrix();
  renderer.setSize(window.innerWidth, window.innerHeight);
  requestRender();
});
requestRender();

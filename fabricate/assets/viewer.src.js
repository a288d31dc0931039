/*
 * Source of fabricate/assets/three-viewer.min.js: the interactive 3D view of
 * report.html.  Bundled with three.js (MIT, https://threejs.org) by
 * fabricate/assets/build_viewer.sh into one classic script, so that the page
 * works when opened from disk (file://), where browsers refuse ES modules and
 * fetch().
 *
 * window.FabViewer.show(element, glbBase64) parses the GLB with GLTFLoader,
 * frames it and renders it with orbit controls.  Progress is written to
 * element.dataset.viewer: "loading" -> "parsed" -> "ready" (first frame drawn),
 * or "no-webgl" / "error"; element.dataset.meshes / .triangles count what was
 * parsed, element.dataset.painted is the fraction of canvas pixels the first
 * frame drew over the background, and document.title gets " [3D ready]".
 */
import {
  AmbientLight, Box3, Color, DirectionalLight, PerspectiveCamera, Scene, Vector3, WebGLRenderer,
} from 'three';
import { GLTFLoader } from 'three/addons/loaders/GLTFLoader.js';
import { OrbitControls } from 'three/addons/controls/OrbitControls.js';

function decodeBase64(text) {
  const bin = atob(text.replace(/\s+/g, ''));
  const bytes = new Uint8Array(bin.length);
  for (let i = 0; i < bin.length; i++) bytes[i] = bin.charCodeAt(i);
  return bytes.buffer;
}

function countScene(root) {
  let meshes = 0, triangles = 0;
  root.traverse((o) => {
    if (!o.isMesh) return;
    meshes += 1;
    const g = o.geometry;
    triangles += (g.index ? g.index.count : g.attributes.position.count) / 3;
  });
  return { meshes, triangles };
}

function paintedFraction(renderer) {
  // share of pixels of the first frame that differ from the background colour
  const gl = renderer.getContext();
  const w = gl.drawingBufferWidth, h = gl.drawingBufferHeight;
  const px = new Uint8Array(w * h * 4);
  gl.readPixels(0, 0, w, h, gl.RGBA, gl.UNSIGNED_BYTE, px);
  const bg = [0xf4, 0xf5, 0xf7];
  let painted = 0;
  for (let i = 0; i < px.length; i += 4) {
    if (Math.abs(px[i] - bg[0]) + Math.abs(px[i + 1] - bg[1]) + Math.abs(px[i + 2] - bg[2]) > 12) painted++;
  }
  return painted / (w * h);
}

function addToggles(el, model, redraw) {
  // one checkbox per named part of the scene (design, glass, beams, layers)
  const box = document.createElement('div');
  box.className = 'viewer-layers';
  box.style.cssText = 'position:absolute;top:8px;right:8px;background:rgba(255,255,255,.85);' +
    'padding:4px 8px;border-radius:4px;font:12px sans-serif';
  for (const child of model.children) {
    const label = document.createElement('label');
    label.style.display = 'block';
    const input = document.createElement('input');
    input.type = 'checkbox';
    input.checked = !(child.userData && child.userData.hidden);
    child.visible = input.checked;
    input.addEventListener('change', () => { child.visible = input.checked; redraw(); });
    label.append(input, ' ' + (child.name || 'part').replace(/_/g, ' '));
    box.appendChild(label);
  }
  el.appendChild(box);
}

function say(el, state, text) {
  el.dataset.viewer = state;
  const note = el.querySelector('.viewer-note');
  if (note) note.textContent = text;
}

function show(el, glbBase64) {
  say(el, 'loading', 'loading the 3D model...');
  let buffer;
  try {
    buffer = decodeBase64(glbBase64);
  } catch (err) {
    say(el, 'error', 'the embedded model is not valid base64: ' + err);
    return;
  }
  new GLTFLoader().parse(buffer, '', (gltf) => {
    const counts = countScene(gltf.scene);
    el.dataset.meshes = String(counts.meshes);
    el.dataset.triangles = String(counts.triangles);
    say(el, 'parsed', `model: ${counts.meshes} meshes, ${counts.triangles} triangles`);
    let renderer;
    try {
      renderer = new WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
    } catch (err) {
      say(el, 'no-webgl', `model parsed (${counts.meshes} meshes, ${counts.triangles} triangles) ` +
        'but this browser has no WebGL to draw it: ' + err.message);
      return;
    }
    start(el, renderer, gltf.scene, counts);
  }, (err) => say(el, 'error', 'the 3D model could not be read: ' + (err && err.message || err)));
}

function start(el, renderer, model, counts) {
  const width = el.clientWidth || 800, height = el.clientHeight || 500;
  renderer.setPixelRatio(window.devicePixelRatio || 1);
  renderer.setSize(width, height);
  el.appendChild(renderer.domElement);

  const scene = new Scene();
  scene.background = new Color(0xf4f5f7);
  scene.add(new AmbientLight(0xffffff, 1.2));
  const sun = new DirectionalLight(0xffffff, 2.0);
  sun.position.set(1, 2, 1.5);
  scene.add(sun);
  scene.add(model);

  const box = new Box3().setFromObject(model);
  const size = box.getSize(new Vector3()).length() || 1;
  const centre = box.getCenter(new Vector3());
  const camera = new PerspectiveCamera(40, width / height, size / 1000, size * 20);
  camera.position.copy(centre).add(new Vector3(0.6, 0.5, 0.9).multiplyScalar(size));
  const controls = new OrbitControls(camera, renderer.domElement);
  controls.target.copy(centre);
  controls.update();

  let drawn = false;
  addToggles(el, model, () => frame());
  function frame() {
    renderer.render(scene, camera);
    if (!drawn) {
      drawn = true;
      el.dataset.painted = paintedFraction(renderer).toFixed(4);
      say(el, 'ready', `drag to rotate, scroll to zoom: ${counts.meshes} meshes, ${counts.triangles} triangles`);
      document.title += ' [3D ready]';
    }
  }
  controls.addEventListener('change', frame);
  window.addEventListener('resize', () => {
    const w = el.clientWidth || width, h = el.clientHeight || height;
    camera.aspect = w / h;
    camera.updateProjectionMatrix();
    renderer.setSize(w, h);
    frame();
  });
  frame();
}

window.FabViewer = { show };

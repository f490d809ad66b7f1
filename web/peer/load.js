// What both peer pages share: the query (`?model=URL&width=W&height=H`), the scene from
// web/peer/scene.mjs's GLB (its one mesh baked into world space, its camera, its one point light),
// the shading constants of raypipe's page, and the status the benchmark reads.
import * as THREE from "three";
import { GLTFLoader } from "three/addons/loaders/GLTFLoader.js";

/// `window.peerStatus`: the frames' times by the page's clock (requestAnimationFrame's
/// timestamps), the scene's size, the adapter, and the first error.
export const status = { frames: 0, times: [], error: null, triangles: 0, renderer: null };
window.peerStatus = status;

/// Lambert with a constant ambient term, as raypipe's page shades a diffuse grey surface.
export const SHADING = {
  albedo: new THREE.Color(0.7, 0.7, 0.7),
  background: new THREE.Color(0.2, 0.2, 0.3),
  ambient: 0.1,
};

/// The page's size and scene: `{ width, height, geometry, camera, lightPosition, lightColor, rayBias }`.
export async function loadScene() {
  const query = new URLSearchParams(window.location.search);
  const width = Number(query.get("width") ?? 320);
  const height = Number(query.get("height") ?? 240);
  const model = query.get("model");
  if (!model) throw new Error("peer: give ?model=URL");

  const gltf = await new GLTFLoader().loadAsync(new URL(model, window.location.href).href);
  gltf.scene.updateMatrixWorld(true);
  let mesh = null;
  let light = null;
  gltf.scene.traverse((o) => {
    if (o.isMesh && !mesh) mesh = o;
    if (o.isPointLight && !light) light = o;
  });
  const camera = gltf.cameras[0];
  if (!mesh || !light || !camera) throw new Error(`${model}: needs a mesh, a point light and a camera`);
  const geometry = mesh.geometry.clone().applyMatrix4(mesh.matrixWorld);
  geometry.computeBoundingSphere();
  camera.aspect = width / height;
  camera.updateProjectionMatrix();
  camera.updateMatrixWorld(true);
  status.triangles = geometry.index.count / 3;
  return {
    width,
    height,
    geometry,
    camera,
    lightPosition: light.getWorldPosition(new THREE.Vector3()),
    lightColor: light.color.clone().multiplyScalar(light.intensity),
    rayBias: geometry.boundingSphere.radius * 1e-4,
  };
}

/// Runs `render` on every animation frame and logs the frame's timestamp.
export function everyFrame(render) {
  const frame = (time) => {
    render();
    status.frames += 1;
    status.times.push(time);
    requestAnimationFrame(frame);
  };
  requestAnimationFrame(frame);
}

/// Records what stopped the page; the benchmark prints it.
export function fail(error) {
  status.error = String(error?.message ?? error);
}

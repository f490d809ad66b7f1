// The peer benchmark's scene as one binary glTF that both tracers read: a model's triangles in its
// own units with smooth vertex normals (both tracers interpolate them, and a shadow ray leaves only
// where the interpolated normal faces the light), one grey diffuse material (Lambert alone: its
// KHR_materials_specular factor 0 turns off the specular lobe, so raypipe traces no reflected
// ray either, as the peer does not), a pinhole camera that frames its bounding sphere, and one
// point light (KHR_lights_punctual). The material is double-sided, as the peer's walk meets both
// sides of a triangle. A file with a camera gets no floor in raypipe, so the workload is the model
// alone.
import fs from "node:fs";
import path from "node:path";
import { Box3, Matrix4, Quaternion, Sphere, Vector3 } from "three";
import { OBJLoader } from "three/addons/loaders/OBJLoader.js";
import { PLYLoader } from "three/addons/loaders/PLYLoader.js";

/// Vertical field of view, radians: the sphere fills the frame's height with a margin.
const FOV_Y = (40 * Math.PI) / 180;

/// The triangles of a PLY or OBJ file with three.js's area-weighted vertex normals:
/// `{ positions: Float32Array, normals: Float32Array, indices: Uint32Array }`.
export function readTriangles(file) {
  const bytes = fs.readFileSync(file);
  const data = bytes.buffer.slice(bytes.byteOffset, bytes.byteOffset + bytes.byteLength);
  const extension = path.extname(file).toLowerCase();
  let geometry;
  if (extension === ".ply") {
    geometry = new PLYLoader().parse(data);
  } else if (extension === ".obj") {
    const meshes = [];
    new OBJLoader().parse(bytes.toString("utf8")).traverse((o) => o.isMesh && meshes.push(o.geometry));
    if (meshes.length !== 1) throw new Error(`${file}: expected one mesh, found ${meshes.length}`);
    geometry = meshes[0];
  } else {
    throw new Error(`${file}: the peer benchmark reads .ply and .obj`);
  }
  if (!geometry.getAttribute("position")?.array.every(Number.isFinite)) {
    throw new Error(`${file}: a vertex is missing or not a finite number`);
  }
  if (!geometry.index) geometry.setIndex([...Array(geometry.getAttribute("position").count).keys()]);
  if (geometry.index.count === 0 || geometry.index.count % 3 !== 0) throw new Error(`${file}: no triangles`);
  geometry.computeVertexNormals();
  const normals = Float32Array.from(geometry.getAttribute("normal").array);
  // A vertex no triangle uses has no normal; glTF wants unit length all the same.
  for (let i = 0; i < normals.length; i += 3) {
    if (normals[i] === 0 && normals[i + 1] === 0 && normals[i + 2] === 0) normals[i + 1] = 1;
  }
  return {
    positions: Float32Array.from(geometry.getAttribute("position").array),
    normals,
    indices: Uint32Array.from(geometry.index.array),
  };
}

/// The GLB of `triangles` framed for a `width` x `height` image; `skew` turns the camera about its
/// up axis by that many degrees (the benchmark's own test: a view that differs must fail validation).
export function sceneGlb({ positions, normals, indices }, width, height, skew = 0) {
  const box = new Box3();
  for (let i = 0; i < positions.length; i += 3) box.expandByPoint(new Vector3(positions[i], positions[i + 1], positions[i + 2]));
  const sphere = box.getBoundingSphere(new Sphere());
  const aspect = width / height;
  const fovX = 2 * Math.atan(Math.tan(FOV_Y / 2) * aspect);
  const distance = (sphere.radius * 1.05) / Math.sin(Math.min(FOV_Y, fovX) / 2);
  const eye = sphere.center.clone().add(new Vector3(0, 0.15, 1).normalize().multiplyScalar(distance));
  const look = new Matrix4().lookAt(eye, sphere.center, new Vector3(0, 1, 0));
  look.premultiply(new Matrix4().makeRotationY((skew * Math.PI) / 180));
  const rotation = new Quaternion().setFromRotationMatrix(look);
  const light = sphere.center.clone().add(new Vector3(1.5, 2.5, 2).multiplyScalar(sphere.radius));

  const indexBytes = indices.byteLength;
  const vectorBytes = positions.byteLength;
  const bytes = (array) => Buffer.from(array.buffer, array.byteOffset, array.byteLength);
  const binary = Buffer.concat([bytes(indices), bytes(positions), bytes(normals)]);
  const vertexCount = positions.length / 3;
  let maxIndex = 0;
  for (const i of indices) maxIndex = Math.max(maxIndex, i);

  const json = {
    asset: { version: "2.0", generator: "raypipe web/peer/scene.mjs" },
    extensionsUsed: ["KHR_lights_punctual", "KHR_materials_specular"],
    extensions: { KHR_lights_punctual: { lights: [{ type: "point", color: [1, 1, 1], intensity: 1 }] } },
    scene: 0,
    scenes: [{ nodes: [0, 1, 2] }],
    nodes: [
      { mesh: 0 },
      { camera: 0, translation: eye.toArray(), rotation: rotation.toArray() },
      { translation: light.toArray(), extensions: { KHR_lights_punctual: { light: 0 } } },
    ],
    cameras: [{ type: "perspective", perspective: { yfov: FOV_Y, aspectRatio: aspect, znear: distance * 1e-3 } }],
    meshes: [{ primitives: [{ attributes: { POSITION: 1, NORMAL: 2 }, indices: 0, material: 0 }] }],
    materials: [{
      pbrMetallicRoughness: { baseColorFactor: [0.7, 0.7, 0.7, 1], metallicFactor: 0, roughnessFactor: 1 },
      doubleSided: true,
      extensions: { KHR_materials_specular: { specularFactor: 0 } },
    }],
    accessors: [
      { bufferView: 0, componentType: 5125, count: indices.length, type: "SCALAR", min: [0], max: [maxIndex] },
      { bufferView: 1, componentType: 5126, count: vertexCount, type: "VEC3", min: box.min.toArray(), max: box.max.toArray() },
      { bufferView: 2, componentType: 5126, count: vertexCount, type: "VEC3" },
    ],
    bufferViews: [
      { buffer: 0, byteOffset: 0, byteLength: indexBytes, target: 34963 },
      { buffer: 0, byteOffset: indexBytes, byteLength: vectorBytes, target: 34962 },
      { buffer: 0, byteOffset: indexBytes + vectorBytes, byteLength: vectorBytes, target: 34962 },
    ],
    buffers: [{ byteLength: binary.length }],
  };
  return glb(json, binary);
}

/// A GLB container: the header, the JSON chunk padded with spaces, the binary chunk with zeros.
function glb(json, binary) {
  const pad = (buffer, fill) => Buffer.concat([buffer, Buffer.alloc((4 - (buffer.length % 4)) % 4, fill)]);
  const text = pad(Buffer.from(JSON.stringify(json)), 0x20);
  const data = pad(binary, 0);
  const chunk = (type, body) => {
    const head = Buffer.alloc(8);
    head.writeUInt32LE(body.length, 0);
    head.writeUInt32LE(type, 4);
    return Buffer.concat([head, body]);
  };
  const body = Buffer.concat([chunk(0x4e4f534a, text), chunk(0x004e4942, data)]);
  const header = Buffer.alloc(12);
  header.writeUInt32LE(0x46546c67, 0);
  header.writeUInt32LE(2, 4);
  header.writeUInt32LE(12 + body.length, 8);
  return Buffer.concat([header, body]);
}

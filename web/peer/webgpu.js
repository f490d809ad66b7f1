// three-mesh-bvh's WebGPU path (`three-mesh-bvh/webgpu`), set up as its compute examples do: a
// BVHComputeData over the mesh's default MeshBVH (the one the WebGL2 peer walks) in storage buffers,
// and its `raycastFirstHit` WGSL walk called from a compute kernel with one invocation per pixel,
// writing a storage texture that a full-screen quad shows. The workload is the WebGL2 peer's: a
// primary ray per pixel and, where it hits and the interpolated normal faces the light, one shadow
// ray, bounded by the light's distance (the API's `maxDist`).
//
//   peer/index.html?backend=webgpu&model=URL&width=W&height=H
//
// A frame (the kernel, then the quad) is submitted on every animation frame; `window.peerStatus`
// publishes the frames' times by the page's clock, and `window.peerCount()` runs the kernel once
// more into a buffer read back on the CPU: `{ hits, shadowRays }`.
import { LinearSRGBColorSpace, Mesh, Vector2 } from "three";
import { Fn, If, instanceIndex, instancedArray, texture, textureStore, uniform, uvec2, vec4 } from "three/tsl";
import { MeshBasicNodeMaterial, QuadMesh, StorageTexture, WebGPURenderer } from "three/webgpu";
import { MeshBVH } from "three-mesh-bvh";
import { BVHComputeData, rayIntersectionResultStruct, rayStruct, wgslTagFn } from "three-mesh-bvh/webgpu";
import { SHADING, everyFrame, fail, loadScene, status } from "./load.js";

async function main() {
  const { width, height, geometry, camera, lightPosition, lightColor, rayBias } = await loadScene();
  if (!navigator.gpu) throw new Error("this browser has no WebGPU (navigator.gpu)");
  const canvas = document.getElementById("frame");
  const renderer = new WebGPURenderer({ canvas, antialias: false });
  await renderer.init();
  if (!renderer.backend.isWebGPUBackend) throw new Error("three's WebGPURenderer fell back to WebGL2: no WebGPU adapter");
  renderer.setPixelRatio(1);
  renderer.setSize(width, height);
  // The kernel writes display values (gamma 2.2, as the WebGL2 peer); the quad passes them through.
  renderer.outputColorSpace = LinearSRGBColorSpace;
  const info = renderer.backend.device.adapterInfo ?? {};
  status.renderer = `WebGPU ${[info.vendor, info.architecture, info.description].filter(Boolean).join(" ")}`.trim();
  renderer.backend.device.addEventListener("uncapturederror", (event) => fail(`the peer's WebGPU: ${event.error.message}`));

  const built = performance.now();
  geometry.boundsTree = new MeshBVH(geometry);
  const bvh = new BVHComputeData(new Mesh(geometry), { attributes: { position: "vec4f", normal: "vec4f" } });
  bvh.update();
  status.buildMs = performance.now() - built;

  const u = {
    size: uniform(new Vector2(width, height)),
    cameraWorld: uniform(camera.matrixWorld),
    inverseProjection: uniform(camera.projectionMatrixInverse),
    lightPosition: uniform(lightPosition),
    lightColor: uniform(lightColor),
    albedo: uniform(SHADING.albedo),
    background: uniform(SHADING.background),
    ambient: uniform(SHADING.ambient),
    rayBias: uniform(rayBias),
  };
  // The pixel's display color (the WebGL2 peer's: gamma 2.2 where it hits) and what it traced: w = 0
  // for a miss, 1 for a hit, 2 for a hit that sent a shadow ray. The camera ray is the WebGL2 peer's
  // (three-mesh-bvh's GLSL ndcToCameraRay).
  const tracePixel = wgslTagFn/* wgsl */ `
    fn tracePixel(pixel: vec2u) -> vec4f {
      let ndc = vec2f(
        (f32(pixel.x) + 0.5) / ${u.size}.x * 2.0 - 1.0,
        1.0 - (f32(pixel.y) + 0.5) / ${u.size}.y * 2.0);
      let lookDirection = ${u.cameraWorld} * vec4f(0.0, 0.0, -1.0, 0.0);
      let nearVector = ${u.inverseProjection} * vec4f(0.0, 0.0, -1.0, 1.0);
      let near = abs(nearVector.z / nearVector.w);
      let eye = ${u.cameraWorld} * vec4f(0.0, 0.0, 0.0, 1.0);
      var toPixel = ${u.inverseProjection} * vec4f(ndc, 0.5, 1.0);
      toPixel = toPixel / toPixel.w;
      let along = ${u.cameraWorld} * toPixel - eye;
      var ray: ${rayStruct};
      ray.origin = eye.xyz + along.xyz * near / dot(along, lookDirection);
      ray.direction = normalize(along.xyz);
      ray.maxDist = 0.0;

      var hit: ${rayIntersectionResultStruct};
      if (!${bvh.fns.raycastFirstHit}(ray, &hit)) {
        return vec4f(${u.background}, 0.0);
      }
      let position = ray.origin + ray.direction * hit.dist;
      let normal = hit.normal * select(1.0, -1.0, dot(hit.normal, ray.direction) > 0.0);
      let b = hit.barycoord;
      var shading = normalize(
        ${bvh.storage.attributes}[hit.indices.x].normal.xyz * b.x +
        ${bvh.storage.attributes}[hit.indices.y].normal.xyz * b.y +
        ${bvh.storage.attributes}[hit.indices.z].normal.xyz * b.z);
      if (dot(shading, normal) < 0.0) {
        shading = -shading;
      }
      let toLight = ${u.lightPosition} - position;
      let lightDistance = length(toLight);
      let l = toLight / lightDistance;
      let nDotL = dot(shading, l);
      var color = ${u.ambient} * ${u.albedo};
      var traced = 1.0;
      if (nDotL > 0.0) {
        traced = 2.0;
        var shadow: ${rayStruct};
        shadow.origin = position + normal * ${u.rayBias};
        shadow.direction = l;
        shadow.maxDist = lightDistance;
        var blocker: ${rayIntersectionResultStruct};
        if (!${bvh.fns.raycastFirstHit}(shadow, &blocker)) {
          color += ${u.lightColor} * ${u.albedo} * nDotL;
        }
      }
      return vec4f(pow(clamp(color, vec3f(0.0), vec3f(1.0)), vec3f(1.0 / 2.2)), traced);
    }
  `;

  const pixels = width * height;
  const pixelOf = (index) => uvec2(index.mod(width), index.div(width));
  const image = new StorageTexture(width, height);
  const trace = Fn(() => {
    If(instanceIndex.lessThan(pixels), () => {
      const pixel = pixelOf(instanceIndex);
      textureStore(image, pixel, vec4(tracePixel(pixel).xyz, 1)).toWriteOnly();
    });
  })().compute(pixels);
  const codes = instancedArray(pixels, "uint");
  const count = Fn(() => {
    If(instanceIndex.lessThan(pixels), () => {
      codes.element(instanceIndex).assign(tracePixel(pixelOf(instanceIndex)).w.toUint());
    });
  })().compute(pixels);

  const display = new MeshBasicNodeMaterial();
  display.colorNode = texture(image);
  const quad = new QuadMesh(display);

  window.peerCount = async () => {
    renderer.compute(count);
    const traced = new Uint32Array(await renderer.getArrayBufferAsync(codes.value));
    let hits = 0;
    let shadowRays = 0;
    for (const code of traced) {
      hits += code >= 1;
      shadowRays += code === 2;
    }
    return { hits, shadowRays };
  };

  everyFrame(() => {
    renderer.compute(trace);
    quad.render(renderer);
  });
}

main().catch(fail);

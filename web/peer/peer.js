// three-mesh-bvh's shader BVH on WebGL2, set up as its own examples do (a MeshBVH with the default
// options packed into data textures by MeshBVHUniformStruct, bvhIntersectFirstHit from a full-screen
// quad), tracing the workload of raypipe's page at depth 1: a primary ray per pixel and, where it
// hits and the interpolated normal faces the light, one shadow ray.
//
//   peer/index.html?model=URL&width=W&height=H
//
// The model is web/peer/scene.mjs's GLB (web/peer/load.js). A frame is traced on every animation
// frame; `window.peerStatus` publishes the frames' times by the page's clock, and
// `window.peerCount()` traces once more into a target read back on the CPU: `{ hits, shadowRays }`.
import * as THREE from "three";
import { FullScreenQuad } from "three/addons/postprocessing/Pass.js";
import { BVHShaderGLSL, FloatVertexAttributeTexture, MeshBVH, MeshBVHUniformStruct } from "three-mesh-bvh";
import { SHADING, everyFrame, fail, loadScene, status } from "./load.js";

const fragmentShader = /* glsl */ `
  precision highp isampler2D;
  precision highp usampler2D;
  ${BVHShaderGLSL.common_functions}
  ${BVHShaderGLSL.bvh_struct_definitions}
  ${BVHShaderGLSL.bvh_ray_functions}

  uniform BVH bvh;
  uniform sampler2D normalAttribute;
  uniform mat4 cameraWorldMatrix;
  uniform mat4 invProjectionMatrix;
  uniform vec2 resolution;
  uniform vec3 lightPosition;
  uniform vec3 lightColor;
  uniform vec3 albedo;
  uniform vec3 background;
  uniform float ambient;
  uniform float rayBias;

  void main() {
    vec3 origin, direction;
    ndcToCameraRay(gl_FragCoord.xy / resolution * 2.0 - 1.0, cameraWorldMatrix, invProjectionMatrix, origin, direction);
    direction = normalize(direction);

    uvec4 faceIndices;
    vec3 faceNormal, barycoord;
    float side, dist;
    if (!bvhIntersectFirstHit(bvh, origin, direction, faceIndices, faceNormal, barycoord, side, dist)) {
      #if COUNTING
        gl_FragColor = vec4(0.0);
      #else
        gl_FragColor = vec4(background, 1.0);
      #endif
      return;
    }
    vec3 position = origin + direction * dist;
    vec3 normal = faceNormal * (dot(faceNormal, direction) > 0.0 ? -1.0 : 1.0);
    vec3 shading = normalize(textureSampleBarycoord(normalAttribute, barycoord, faceIndices.xyz).xyz);
    if (dot(shading, normal) < 0.0) shading = -shading;

    vec3 toLight = lightPosition - position;
    float lightDistance = length(toLight);
    vec3 l = toLight / lightDistance;
    float nDotL = dot(shading, l);
    bool lit = nDotL > 0.0;
    vec3 color = ambient * albedo;
    if (lit) {
      uvec4 shadowFace;
      vec3 shadowNormal, shadowBary;
      float shadowSide, shadowDist;
      bool blocked = bvhIntersectFirstHit(bvh, position + normal * rayBias, l, shadowFace, shadowNormal, shadowBary,
        shadowSide, shadowDist) && shadowDist > 0.0 && shadowDist < lightDistance;
      if (!blocked) color += lightColor * albedo * nDotL;
    }
    #if COUNTING
      gl_FragColor = vec4(1.0, lit ? 1.0 : 0.0, 0.0, 1.0);
    #else
      gl_FragColor = vec4(pow(clamp(color, 0.0, 1.0), vec3(1.0 / 2.2)), 1.0);
    #endif
  }
`;

const vertexShader = /* glsl */ `
  varying vec2 vUv;
  void main() {
    vUv = uv;
    gl_Position = vec4(position, 1.0);
  }
`;

async function main() {
  const { width, height, geometry, camera, lightPosition, lightColor, rayBias } = await loadScene();
  const built = performance.now();
  const bvh = new MeshBVH(geometry);
  status.buildMs = performance.now() - built;
  const bvhStruct = new MeshBVHUniformStruct();
  bvhStruct.updateFrom(bvh);
  const normals = new FloatVertexAttributeTexture();
  normals.updateFrom(geometry.attributes.normal);

  const canvas = document.getElementById("frame");
  const renderer = new THREE.WebGLRenderer({ canvas, antialias: false });
  // A shader that does not compile is the benchmark's failure, not a black frame.
  renderer.debug.onShaderError = (gl, program, vertex, fragment) => {
    status.error = `the peer's shader: ${gl.getShaderInfoLog(fragment) || gl.getProgramInfoLog(program)}`;
  };
  renderer.setPixelRatio(1);
  renderer.setSize(width, height);
  status.renderer = renderer.getContext().getParameter(renderer.getContext().VERSION);

  const uniforms = {
    bvh: { value: bvhStruct },
    normalAttribute: { value: normals },
    cameraWorldMatrix: { value: camera.matrixWorld },
    invProjectionMatrix: { value: camera.projectionMatrixInverse },
    resolution: { value: new THREE.Vector2(width, height) },
    lightPosition: { value: lightPosition },
    lightColor: { value: lightColor },
    albedo: { value: SHADING.albedo },
    background: { value: SHADING.background },
    ambient: { value: SHADING.ambient },
    rayBias: { value: rayBias },
  };
  const material = (counting) =>
    new THREE.ShaderMaterial({ defines: { COUNTING: counting ? 1 : 0 }, uniforms, vertexShader, fragmentShader });
  const quad = new FullScreenQuad(material(false));
  const counter = new FullScreenQuad(material(true));

  window.peerCount = () => {
    const target = new THREE.WebGLRenderTarget(width, height);
    renderer.setRenderTarget(target);
    counter.render(renderer);
    const pixels = new Uint8Array(width * height * 4);
    renderer.readRenderTargetPixels(target, 0, 0, width, height, pixels);
    renderer.setRenderTarget(null);
    target.dispose();
    let hits = 0;
    let shadowRays = 0;
    for (let i = 0; i < pixels.length; i += 4) {
      hits += pixels[i] > 127;
      shadowRays += pixels[i + 1] > 127;
    }
    return { hits, shadowRays };
  };

  everyFrame(() => quad.render(renderer));
}

main().catch(fail);

// Surfaces and Whitted shading: Phong direct light with hard shadows, Schlick's Fresnel term.
// Mirrored by src/cpu/shade.rs.

// Secondary rays start RAY_BIAS (from the preamble) times the hit's reach off the surface, to escape
// it; the offset scales with the scene, so a scene renders alike at any size in the accepted range.

struct Surface {
    position: vec3<f32>,
    // Geometric, unit, pointing out of the primitive: it decides inside and outside, and which side
    // new rays start on.
    normal: vec3<f32>,
    // Unit, on the geometric normal's side: the interpolated vertex normal of a smooth triangle, the
    // geometric normal otherwise. Lighting, reflection and refraction use it.
    shading: vec3<f32>,
    material: u32,
    // The largest coordinate of the ray's origin and of the hit: the position's rounding error is a
    // few float steps of it.
    reach: f32,
}

fn max_abs(v: vec3<f32>) -> f32 {
    return max(abs(v.x), max(abs(v.y), abs(v.z)));
}

// normalize(v) for any nonzero v: the squares of a big or small v would overflow or underflow.
fn normalize_scaled(v: vec3<f32>) -> vec3<f32> {
    return normalize(v / max_abs(v));
}

// A smooth triangle's vertex normals interpolated at the hit, turned to the geometric normal's side;
// the geometric normal where they cancel out.
fn triangle_shading(triangle: Triangle, ray: Ray, normal: vec3<f32>) -> vec3<f32> {
    if (triangle.normals == NONE) {
        return normal;
    }
    let uvt = triangle_uvt(triangle, ray);
    let n = load_triangle_normals(triangle.normals);
    let blended = (1.0 - uvt.x - uvt.y) * n.n0 + uvt.x * n.n1 + uvt.y * n.n2;
    if (dot(blended, blended) == 0.0) {
        return normal;
    }
    let shading = normalize(blended);
    return select(shading, -shading, dot(shading, normal) < 0.0);
}

fn surface_at(ray: Ray, hit: Hit) -> Surface {
    let position = ray.origin + hit.t * ray.dir;
    let reach = max(max_abs(ray.origin), max_abs(position));
    if (hit.kind == HIT_PRIMITIVE) {
        if (hit.index < globals.scene.sphere_count) {
            let sphere = load_sphere(hit.index);
            let normal = normalize(position - sphere.center);
            return Surface(position, normal, normal, sphere.material, reach);
        }
        let triangle = load_triangle(hit.index - globals.scene.sphere_count);
        let normal = normalize_scaled(cross(triangle.v1 - triangle.v0, triangle.v2 - triangle.v0));
        return Surface(position, normal, triangle_shading(triangle, ray, normal), triangle.material, reach);
    }
    let plane = load_plane(hit.index);
    let local = position - plane.point;
    let cell = floor(dot(local, plane.tangent) / plane.checker_size)
        + floor(dot(local, plane.bitangent) / plane.checker_size);
    var material = plane.material;
    if (cell - 2.0 * floor(cell * 0.5) != 0.0) {
        material = plane.checker_material;
    }
    return Surface(position, plane.normal, plane.normal, material, reach);
}

// `side` points to where the new ray goes: the facing normal for reflection and shadows, its
// opposite for refraction.
fn offset_origin(surface: Surface, side: vec3<f32>) -> vec3<f32> {
    return surface.position + side * (RAY_BIAS * surface.reach);
}

// Schlick's approximation of the Fresnel reflectance; cos_theta is taken on the less dense side.
fn fresnel_schlick(cos_theta: f32, ior: f32) -> f32 {
    let r = (1.0 - ior) / (1.0 + ior);
    let r0 = r * r;
    let x = 1.0 - cos_theta;
    let x2 = x * x;
    return r0 + (1.0 - r0) * x2 * x2 * x;
}

// Ambient plus, for every light that the surface faces and that nothing blocks, Lambert and Phong.
// `normal` (geometric) and `shading` face the viewer; `view` points from the surface to the viewer.
fn direct_light(surface: Surface, normal: vec3<f32>, shading: vec3<f32>, view: vec3<f32>, material: Material) -> vec3<f32> {
    var color = globals.scene.ambient * material.color;
    let origin = offset_origin(surface, normal);
    for (var i = 0u; i < globals.scene.light_count; i++) {
        let light = load_light(i);
        let to_light = light.position - surface.position;
        let distance = length(to_light);
        let l = to_light / distance;
        let n_dot_l = dot(shading, l);
        if (n_dot_l <= 0.0) {
            continue;
        }
        ray_count += 1u;
        if (occluded(make_ray(origin, l), distance)) {
            continue;
        }
        var highlight = 0.0;
        let r_dot_v = dot(reflect(-l, shading), view);
        if (r_dot_v > 0.0 && material.specular > 0.0) {
            highlight = material.specular * pow(r_dot_v, material.shininess);
        }
        color += light.color * (material.color * n_dot_l + vec3<f32>(highlight));
    }
    return color;
}

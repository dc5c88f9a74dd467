// normal_map.glsl — the shading normal with a material's normal texture applied (glTF §3.9.3):
// (x, y, z) = 2·texel − 1, x and y times normalTexture.scale, n' = normalize(T·x + B·y + N·z),
// T the interpolated TANGENT Gram-Schmidt orthogonalised against N, B = (N × T)·w (§3.7.2.1).
// The same arithmetic scn_normal_at (normal_map.c) does for a CPU hit. The including stage
// declares v_uv0, v_uv1 and v_tangent (world xyz, handedness w); eng_bind_material sets the
// uniforms (u_nrm_tex_on 0 where the material has no normal texture or the draw no tangents).
uniform sampler2D u_nrm_tex;
uniform int u_nrm_tex_on;
uniform int u_nrm_uv_set;
uniform mat3 u_nrm_uv_xf;
uniform float u_nrm_scale;

vec3 normal_mapped(vec3 n)
{
    if (u_nrm_tex_on != 1)
        return n;
    vec3 t = v_tangent.xyz - n * dot(n, v_tangent.xyz);
    float len = length(t);
    if (!(len > 0.0))
        return n;
    t /= len;
    vec3 b = cross(n, t) * (v_tangent.w < 0.0 ? -1.0 : 1.0);
    vec3 m = texture(u_nrm_tex, (u_nrm_uv_xf * vec3(u_nrm_uv_set == 1 ? v_uv1 : v_uv0, 1.0)).xy).xyz * 2.0 - 1.0;
    vec3 r = t * (m.x * u_nrm_scale) + b * (m.y * u_nrm_scale) + n * m.z;
    float lr = length(r);
    return lr > 0.0 ? r / lr : n;
}

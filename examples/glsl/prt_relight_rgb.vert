#version 330 core
// Per-vertex PRT relighting of RGB transfer, order 4, for assets baked with a coloured albedo and
// bounces (`prtsub bake --bounces N --albedo vertex|R,G,B` or `--albedo-map`): light that bounced
// off a red wall is red, so each channel has its own 16 coefficients.
//
// Bind, from a glTF asset: POSITION, COLOR_0 (the surface's own linear albedo) and
// _PRT_R_0.._PRT_R_3, _PRT_G_0.._PRT_G_3, _PRT_B_0.._PRT_B_3 (four coefficients to a vec4, as
// prt_relight.vert reads _PRT_j). From a PLY asset: x y z, albedo_r albedo_g albedo_b and
// r_t0..r_t15, g_t0..g_t15, b_t0..b_t15 packed the same way. Channel c dots the light's channel c
// with its own block; the receiver's albedo is not in the transfer (docs/sh_convention.md,
// "Colour"), so an engine with the diffuse texture multiplies it per fragment instead of using
// the vertex albedo here.

layout(location = 0) in vec3 a_position;
layout(location = 1) in vec3 a_albedo;
layout(location = 2) in vec4 a_prt_r[4];
layout(location = 6) in vec4 a_prt_g[4];
layout(location = 10) in vec4 a_prt_b[4];

uniform mat4 u_model_view_projection;
uniform vec3 u_light[16];  // SH coefficients of the light, RGB, index l*(l+1)+m

out vec3 v_radiance;  // linear exit radiance

void main() {
  vec3 sum = vec3(0.0);
  for (int j = 0; j < 4; ++j)
    for (int c = 0; c < 4; ++c) {
      vec3 l = u_light[4 * j + c];
      sum += vec3(l.r * a_prt_r[j][c], l.g * a_prt_g[j][c], l.b * a_prt_b[j][c]);
    }
  v_radiance = a_albedo * (1.0 / 3.14159265358979) * sum;
  gl_Position = u_model_view_projection * vec4(a_position, 1.0);
}

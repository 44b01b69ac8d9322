#version 330 core
// Per-vertex PRT relighting, order 4 (16 coefficients), for assets written by `prtsub bake`.
//
// Bind the asset's vertex attributes: positions, normals (not needed for diffuse PRT but handy
// for debugging) and the transfer t0..t15, four to a vec4 (a_prt_0 = t0..t3, a_prt_1 = t4..t7,
// ...). From a glTF asset these are POSITION, NORMAL and _PRT_0.._PRT_3 as they are (three.js
// names them _prt_0.._prt_3); a quantized one's _PRT_j are normalized SHORTs, read with
// normalization on and scaled by u_prt_scale (extras.quantization.scale; all 1 for FLOAT). From a
// PLY asset, pack x y z, nx ny nz and t0..t15 the same way. Each frame, project the light into SH on the CPU
// (docs/sh_convention.md; `prtsub render --light ...` shows the same result) and upload one RGB
// triple per coefficient. Rotating the light is a 16x16 matrix on the CPU, not work per vertex.
//
// Exit radiance is (albedo / pi) * dot(light, transfer) per channel: a dot product per vertex,
// interpolated linearly by the rasteriser, exactly what `prtsub render` shows (Gouraud).

layout(location = 0) in vec3 a_position;
layout(location = 1) in vec3 a_normal;
layout(location = 2) in vec4 a_prt_0;
layout(location = 3) in vec4 a_prt_1;
layout(location = 4) in vec4 a_prt_2;
layout(location = 5) in vec4 a_prt_3;

uniform mat4 u_model_view_projection;
uniform vec4 u_prt_scale[4];  // per-coefficient scales of a quantized glTF asset, else all 1
uniform vec3 u_light[16];  // SH coefficients of the light, RGB, index l*(l+1)+m
uniform vec3 u_albedo;     // diffuse albedo; 0.8 is prtsub's default

out vec3 v_radiance;  // linear exit radiance

void main() {
  vec4 t[4] = vec4[4](a_prt_0 * u_prt_scale[0], a_prt_1 * u_prt_scale[1], a_prt_2 * u_prt_scale[2],
                      a_prt_3 * u_prt_scale[3]);
  vec3 sum = vec3(0.0);
  for (int j = 0; j < 4; ++j)
    for (int c = 0; c < 4; ++c) sum += u_light[4 * j + c] * t[j][c];
  v_radiance = u_albedo * (1.0 / 3.14159265358979) * sum;
  gl_Position = u_model_view_projection * vec4(a_position, 1.0);
}

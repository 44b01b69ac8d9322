#version 330 core
// Per-vertex PRT relighting, order 4 (16 coefficients), for assets written by `prtsub bake`.
//
// Bind the asset's vertex properties as attributes: positions (x y z), normals (nx ny nz, not
// needed for diffuse PRT but handy for debugging) and the transfer t0..t15 packed four to a
// vec4 (a_t0 = t0..t3, a_t1 = t4..t7, ...). Each frame, project the light into SH on the CPU
// (docs/sh_convention.md; `prtsub render --light ...` shows the same result) and upload one RGB
// triple per coefficient. Rotating the light is a 16x16 matrix on the CPU, not work per vertex.
//
// Exit radiance is (albedo / pi) * dot(light, transfer) per channel: a dot product per vertex,
// interpolated linearly by the rasteriser, exactly what `prtsub render` shows (Gouraud).

layout(location = 0) in vec3 a_position;
layout(location = 1) in vec3 a_normal;
layout(location = 2) in vec4 a_t0;
layout(location = 3) in vec4 a_t1;
layout(location = 4) in vec4 a_t2;
layout(location = 5) in vec4 a_t3;

uniform mat4 u_model_view_projection;
uniform vec3 u_light[16];  // SH coefficients of the light, RGB, index l*(l+1)+m
uniform vec3 u_albedo;     // diffuse albedo; 0.8 is prtsub's default

out vec3 v_radiance;  // linear exit radiance

void main() {
  float t[16] = float[16](a_t0.x, a_t0.y, a_t0.z, a_t0.w, a_t1.x, a_t1.y, a_t1.z, a_t1.w,
                          a_t2.x, a_t2.y, a_t2.z, a_t2.w, a_t3.x, a_t3.y, a_t3.z, a_t3.w);
  vec3 sum = vec3(0.0);
  for (int i = 0; i < 16; ++i) sum += u_light[i] * t[i];
  v_radiance = u_albedo * (1.0 / 3.14159265358979) * sum;
  gl_Position = u_model_view_projection * vec4(a_position, 1.0);
}

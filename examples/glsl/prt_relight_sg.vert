#version 330 core
// Per-vertex PRT relighting of a spherical-Gaussian asset (`prtsub bake --basis sg:12`): 12 lobe
// coefficients per vertex instead of 16 SH ones.
//
// Bind positions, normals and the lobes c0..c11, four to a vec4 (a_prt_0 = c0..c3, ...): from a
// glTF asset, POSITION, NORMAL and _PRT_0.._PRT_2; from a PLY asset, t0..t11. Each frame, the CPU
// works out what every lobe sees of the light, L_k = integral(L * G_k) per colour, and uploads
// those 12 RGB triples. For an SH light of order n it is a closed form (Funk-Hecke; docs/
// sh_convention.md, "Spherical Gaussians"):
//     L_k = sum over l < n, |m| <= l of g_l * y_lm(mu_k) * l_lm,   g_l = 4 pi e^-sharpness i_l(sharpness)
// with mu_k and the sharpness from the asset (sg_axes, sg_sharpness; prtsub's sg_light). Use the
// asset's sg_shading_order for n: the lobes' bands above it carry under 0.2% of their light.
// Rotating the light rotates the SH light (or, equally, the axes) on the CPU, then L_k again:
// 12 * n² multiply-adds a frame, none per vertex.
//
// Exit radiance is (albedo / pi) * dot(L, c) per channel, exactly what `prtsub render` shows
// (Gouraud). With non-negative lobes (the default) the radiance is a sum of c_k >= 0 times L_k;
// integrate a non-negative environment map against the lobes texel by texel (prtsub's sg_light of a
// lat-long image) and every L_k >= 0, so no vertex shades negative, however narrow the light.
// Pair with prt_relight.frag.

layout(location = 0) in vec3 a_position;
layout(location = 1) in vec3 a_normal;
layout(location = 2) in vec4 a_prt_0;
layout(location = 3) in vec4 a_prt_1;
layout(location = 4) in vec4 a_prt_2;

uniform mat4 u_model_view_projection;
uniform vec4 u_prt_scale[3];  // per-coefficient scales of a quantized glTF asset, else all 1
uniform vec3 u_lobe_light[12];  // L_k, RGB: what lobe k sees of the light
uniform vec3 u_albedo;          // diffuse albedo; 0.8 is prtsub's default

out vec3 v_radiance;  // linear exit radiance

void main() {
  vec4 c[3] = vec4[3](a_prt_0 * u_prt_scale[0], a_prt_1 * u_prt_scale[1], a_prt_2 * u_prt_scale[2]);
  vec3 sum = vec3(0.0);
  for (int j = 0; j < 3; ++j)
    for (int k = 0; k < 4; ++k) sum += u_lobe_light[4 * j + k] * c[j][k];
  v_radiance = u_albedo * (1.0 / 3.14159265358979) * sum;
  gl_Position = u_model_view_projection * vec4(a_position, 1.0);
}

#version 330 core
// Tone mapping that matches `prtsub render -o FRAME.png`: scale by exposure, clamp to [0, 1],
// then the sRGB curve. Skip the curve if your framebuffer is GL_SRGB8_ALPHA8 (it encodes for you).

in vec3 v_radiance;
uniform float u_exposure;  // 1.0 matches prtsub's default
out vec4 frag_color;

vec3 linear_to_srgb(vec3 v) {
  v = clamp(v, 0.0, 1.0);
  vec3 low = 12.92 * v;
  vec3 high = 1.055 * pow(v, vec3(1.0 / 2.4)) - 0.055;
  return mix(low, high, step(vec3(0.0031308), v));
}

void main() {
  frag_color = vec4(linear_to_srgb(u_exposure * v_radiance), 1.0);
}

#version 330
in vec3 v_normal;
uniform vec3 DiffuseColor;
uniform vec3 PhongColor;
uniform float Phong;
out vec4 color;
void main() {
  float i = dot(normalize(v_normal), vec3(0.0, 0.0, 1.0));
  color = vec4(i > Phong ? PhongColor : DiffuseColor * (i > 0.5 ? 1.0 : 0.6), 1.0);
}

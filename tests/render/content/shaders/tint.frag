#version 330
// Modern GLSL: flat colour from a uniform, lit by nothing.
in vec3 v_normal;
uniform vec3 Tint;
out vec4 f_color;

void main() {
    f_color = vec4(Tint, 1.0);
}

#version 330
in vec3 in_position;
in vec3 in_normal;
uniform mat4 mvp;
out vec3 v_normal;
void main() { v_normal = in_normal; gl_Position = mvp * vec4(in_position, 1.0); }

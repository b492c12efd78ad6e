// Toon shader vertex stage, written for the fixed-function-era GLSL of the paper (OSG).
varying vec3 Normal;

void main(void)
{
    Normal = normalize(gl_NormalMatrix * gl_Normal);
    gl_Position = ftransform();
}

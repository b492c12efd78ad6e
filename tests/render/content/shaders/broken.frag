// A fragment shader with a typo on line 6.
uniform vec3 Tint;

void main(void)
{
    gl_FragColor = vec4(Tint, 1.0) * undefined_thing;
}

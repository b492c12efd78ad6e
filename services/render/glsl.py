"""GLSL sources of the built-in programs: the default lit material, the shadow depth pass,
the full-screen quad used by post-processing and the HUD.

Interface every mesh program sees (a user's modern shader declares what it uses):

* per vertex: ``in_position`` (vec3), ``in_normal`` (vec3), ``in_uv`` (vec2), ``in_color`` (vec4)
* per instance: ``i_model`` (mat4), ``i_color`` (vec4, the object's colour),
  ``i_flags`` (vec4: x shadower, y shadowed)
* uniforms set when present: ``u_view``, ``u_proj``, ``u_camera_pos``, ``u_time``,
  ``u_texture`` (sampler2D, unit 0), ``u_light_vp`` and ``u_shadow_map`` (unit 1),
  ``u_light_count``, ``u_shadow_light`` and the arrays ``u_light_kind`` (int: 0 directional,
  1 point, 2 spot), ``u_light_pos``, ``u_light_dir``, ``u_light_color`` (colour times
  intensity), ``u_light_cos_cutoff`` (up to 8 lights).
* a simple shader may instead take per-object matrices as uniforms ``mvp``/``u_mvp``,
  ``model``/``u_model``, ``normal_matrix``/``u_normal_matrix`` (mat3); its objects are then
  drawn one call each instead of instanced.
"""

from __future__ import annotations

MAX_LIGHTS = 8

# -- the contract with a user's shader (docs/GLSL.md is generated from these) --------------

#: The GLSL a modern user shader is written in (older or versionless GLSL is mapped onto it).
GLSL_VERSION = "#version 330"

#: Per-vertex inputs of every mesh (name -> GLSL type, meaning).
VERTEX_INPUTS: dict[str, tuple[str, str]] = {
    "in_position": ("vec3", "vertex position, object frame (m)"),
    "in_normal": ("vec3", "vertex normal, object frame"),
    "in_uv": ("vec2", "texture coordinate"),
    "in_color": ("vec4", "vertex colour (white when the model has none)"),
}

#: Per-instance inputs: one value per object drawn.
INSTANCE_INPUTS: dict[str, tuple[str, str]] = {
    "i_model": ("mat4", "object -> world (position, orientation, scale)"),
    "i_color": ("vec4", "the object's Color (RGBA)"),
    "i_flags": ("vec4", "x: casts shadows (Shadower), y: receives them (Shadowed)"),
}

#: Texture units the engine binds, by the sampler uniform it sets to that unit.
TEXTURE_UNITS: dict[str, int] = {"u_texture": 0, "u_shadow_map": 1}

#: Every uniform the renderer sets on a mesh program each frame, when the program has it
#: (name -> GLSL type, meaning); ``Renderer.frame_uniforms`` gives exactly these.
ENGINE_UNIFORMS: dict[str, tuple[str, str]] = {
    "u_view": ("mat4", "world -> camera"),
    "u_proj": ("mat4", "camera -> clip space"),
    "u_camera_pos": ("vec3", "the eye, world frame (m)"),
    "u_time": ("float", "seconds the renderer has drawn (s)"),
    "u_ambient": ("vec3", "ambient light colour"),
    "u_texture": ("sampler2D", "the object's Texture (white without one), unit 0"),
    "u_shadow_map": ("sampler2DShadow", "the shadow map (depth compare), unit 1"),
    "u_shadow_light": ("int", "index of the light casting shadows, -1 for none"),
    "u_light_vp": ("mat4", "world -> the shadow light's clip space"),
    "u_light_count": ("int", f"lights in use (at most {MAX_LIGHTS})"),
    "u_light_kind": (f"int[{MAX_LIGHTS}]", "0 directional, 1 point, 2 spot"),
    "u_light_pos": (f"vec3[{MAX_LIGHTS}]", "light positions, world frame (m)"),
    "u_light_dir": (f"vec3[{MAX_LIGHTS}]", "light directions, world frame"),
    "u_light_color": (f"vec3[{MAX_LIGHTS}]", "light colour times intensity"),
    "u_light_cos_cutoff": (f"float[{MAX_LIGHTS}]", "cosine of a spot light's cone half-angle"),
}

#: Per-object matrices a simple shader may take as uniforms instead of ``i_model``; its
#: objects are then drawn one call each (not instanced). Both spellings are set.
PER_OBJECT_UNIFORMS: dict[str, tuple[str, str]] = {
    "mvp": ("mat4", "object -> clip space (also u_mvp)"),
    "u_mvp": ("mat4", "the same as mvp"),
    "model": ("mat4", "object -> world (also u_model)"),
    "u_model": ("mat4", "the same as model"),
    "normal_matrix": ("mat3", "inverse transpose of model's rotation-scale (also "
                      "u_normal_matrix)"),
    "u_normal_matrix": ("mat3", "the same as normal_matrix"),
}


def contract_markdown() -> str:
    """docs/GLSL.md: what a user's shader gets from the engine (a test keeps the file equal
    to this, so the page cannot drift from the renderer)."""
    def table(rows: dict[str, tuple[str, str]], what: str) -> list[str]:
        out = [f"| {what} | GLSL type | meaning |", "|---|---|---|"]
        out += [f"| `{name}` | `{kind}` | {meaning} |" for name, (kind, meaning) in rows.items()]
        return [*out, ""]

    units = ", ".join(f"{unit}: `{name}`" for name, unit in TEXTURE_UNITS.items())
    return "\n".join([
        "# The GLSL contract",
        "",
        "<!-- generated from services/render/glsl.py by `python -m tools.docs`; "
        "tests/render/test_glsl_contract.py keeps it equal -->",
        "",
        "A `ShaderProgram` of a scene (`VertexShader`/`FragmentShader` files, paper Listing 3)",
        "draws the objects whose `VisualAttributes` name its `ShaderState`. This page is what",
        "the engine gives such a shader.",
        "",
        "## Version",
        "",
        f"Modern shaders are `{GLSL_VERSION}` (core profile) or later and declare the inputs",
        "and uniforms below that they use. Shaders without `#version`, or older than 330,",
        "are fixed-function-era GLSL (`gl_Vertex`, `gl_NormalMatrix`, `ftransform()`,",
        "`gl_FragColor`, `gl_LightSource[i]`, ...): the engine maps those built-ins onto the",
        "inputs below, so the paper's OpenSceneGraph shaders run unchanged. A program that",
        "names only a fragment shader gets the engine's vertex stage, which passes",
        "`v_world`, `v_normal`, `v_uv` and `v_color` to it.",
        "",
        "## Vertex inputs",
        "",
        *table(VERTEX_INPUTS, "per vertex"),
        *table(INSTANCE_INPUTS, "per instance"),
        "## Uniforms the engine sets",
        "",
        "Set before each object batch when the program has them (a compiler drops what a",
        "shader declares but does not use). Matrices are column-major, as GLSL expects.",
        "",
        *table(ENGINE_UNIFORMS, "uniform"),
        "A simple shader may take per-object matrices instead of `i_model`; its objects are",
        "then drawn one call each:",
        "",
        *table(PER_OBJECT_UNIFORMS, "uniform"),
        "## Texture units",
        "",
        f"{units}. A sampler of your own needs a `Uniform` giving its unit.",
        "",
        "## Your own uniforms",
        "",
        "Every other uniform is yours: give it a value in the `ShaderState` (`Uniform { ID",
        "\"Edge\" Value 0.64 }`) or from Lua (`setUniform(\"toon\", \"Edge\", 0.5)`). A uniform",
        "that neither the engine nor the scene nor a script sets stays 0 (a zero matrix draws",
        "nothing), so the renderer warns once, naming the uniform, the shader file and the",
        "closest name the engine supplies (`u_projection`: did you mean `u_proj`?).",
        "",
    ])


#: Per-vertex and per-instance inputs every mesh program takes (see Renderer's buffers).
MESH_INPUTS = """
in vec3 in_position;
in vec3 in_normal;
in vec2 in_uv;
in vec4 in_color;
in mat4 i_model;
in vec4 i_color;
uniform mat4 u_view;
uniform mat4 u_proj;
"""

LIT_VERTEX = "#version 330" + MESH_INPUTS + """in vec4 i_flags;
uniform mat4 u_light_vp;
out vec3 v_world;
out vec3 v_normal;
out vec2 v_uv;
out vec4 v_color;
out vec4 v_light_clip;
out float v_shadowed;
void main() {
    vec4 world = i_model * vec4(in_position, 1.0);
    mat3 m = mat3(i_model);  // rotation times scale: its inverse-transpose is m / scale^2
    vec3 s2 = vec3(dot(m[0], m[0]), dot(m[1], m[1]), dot(m[2], m[2]));
    v_world = world.xyz;
    v_normal = m * (in_normal / s2);
    v_uv = in_uv;
    v_color = in_color * i_color;
    v_light_clip = u_light_vp * world;
    v_shadowed = i_flags.y;
    gl_Position = u_proj * (u_view * world);
}
"""

#: The lit vertex stage drawing both eyes of a stereo view in one pass (instanced stereo):
#: each part is two instances (its instance row read twice: a divisor of 2), the even one
#: the left eye, the odd one the right; each lands in its half of the side-by-side target,
#: clipped at the middle (``gl_ClipDistance``), so a stereo frame costs the CPU about what
#: a mono one does.
LIT_VERTEX_STEREO = LIT_VERTEX.replace("uniform mat4 u_light_vp;\n", """uniform mat4 u_light_vp;
uniform mat4 u_eye_view[2];
uniform mat4 u_eye_proj[2];
uniform vec3 u_eye_pos[2];
flat out vec3 v_eye_pos;
out float gl_ClipDistance[1];
""").replace("    gl_Position = u_proj * (u_view * world);\n", """    int eye = gl_InstanceID & 1;
    v_eye_pos = u_eye_pos[eye];
    vec4 clip = u_eye_proj[eye] * (u_eye_view[eye] * world);
    float side = eye == 0 ? -1.0 : 1.0;
    gl_ClipDistance[0] = clip.w + side * clip.x;  // inside this eye's half
    clip.x = 0.5 * clip.x + 0.5 * side * clip.w;
    gl_Position = clip;
""")

#: The lit fragment stage is specialised per light set (``LIGHT_KINDS`` and ``SHADOW_LIGHT``
#: are compile-time constants) so loops unroll: llvmpipe shades far faster without dynamic
#: indexing; and per textured or not. :func:`lit_fragment` fills them in.
LIT_FRAGMENT_TEMPLATE = """
#version 330
#define N_LIGHTS %(n)d
#define SHADOW_LIGHT %(shadow)d
#define TEXTURED %(textured)d
const int LIGHT_KINDS[N_LIGHTS] = int[N_LIGHTS](%(kinds)s);
in vec3 v_world;
in vec3 v_normal;
in vec2 v_uv;
in vec4 v_color;
in vec4 v_light_clip;
in float v_shadowed;
uniform sampler2D u_texture;
uniform sampler2DShadow u_shadow_map;
uniform vec3 u_camera_pos;
uniform vec3 u_ambient;
uniform vec3 u_light_pos[N_LIGHTS];
uniform vec3 u_light_dir[N_LIGHTS];
uniform vec3 u_light_color[N_LIGHTS];
uniform float u_light_cos_cutoff[N_LIGHTS];
out vec4 f_color;

float shadow_factor() {
    vec3 p = v_light_clip.xyz / v_light_clip.w * 0.5 + 0.5;
    if (p.x <= 0.0 || p.x >= 1.0 || p.y <= 0.0 || p.y >= 1.0) return 1.0;
    return texture(u_shadow_map, vec3(p.xy, min(p.z, 1.0) - 0.002));  // 2x2 PCF in hardware
}

void main() {
    vec4 albedo = TEXTURED == 1 ? texture(u_texture, v_uv) * v_color : v_color;
    vec3 n = normalize(v_normal);
    vec3 to_eye = normalize(u_camera_pos - v_world);
    if (dot(n, to_eye) < 0.0) n = -n;  // two-sided lighting for open meshes and planes
    vec3 light = u_ambient;
    vec3 spec = vec3(0.0);
    for (int i = 0; i < N_LIGHTS; ++i) {
        vec3 l;
        float att = 1.0;
        if (LIGHT_KINDS[i] == 0) {
            l = -normalize(u_light_dir[i]);
        } else {
            vec3 d = u_light_pos[i] - v_world;
            float dist = length(d);
            l = d / max(dist, 1e-6);
            att = 1.0 / (1.0 + 0.02 * dist * dist);
            if (LIGHT_KINDS[i] == 2) {
                float c = dot(-l, normalize(u_light_dir[i]));
                att *= smoothstep(u_light_cos_cutoff[i], mix(u_light_cos_cutoff[i], 1.0, 0.2), c);
            }
        }
        float diff = max(dot(n, l), 0.0);
        if (i == SHADOW_LIGHT && v_shadowed > 0.5 && diff > 0.0) att *= shadow_factor();
        light += u_light_color[i] * (diff * att);
        float s = max(dot(n, normalize(l + to_eye)), 0.0) * step(0.0, diff);
        s *= s; s *= s; s *= s; s *= s; s *= s;  // s^32 without pow
        spec += u_light_color[i] * (s * 0.15 * att);
    }
    f_color = vec4(albedo.rgb * light + spec, albedo.a);
}
"""


def lit_fragment(kinds: tuple[int, ...], shadow_light: int, textured: bool = True,
                 stereo: bool = False) -> str:
    """The lit fragment source for lights of ``kinds`` (0 directional, 1 point, 2 spot);
    without ``textured`` it skips the texture fetch (objects with no Texture: a CPU
    rasteriser shades them a few per cent faster); ``stereo``: after
    :data:`LIT_VERTEX_STEREO`, the eye's position comes from the vertex stage."""
    kinds = kinds or (0,)
    source = LIT_FRAGMENT_TEMPLATE % {"n": len(kinds), "shadow": shadow_light,
                                      "kinds": ", ".join(str(k) for k in kinds),
                                      "textured": int(textured)}
    if stereo:
        source = source.replace("uniform vec3 u_camera_pos;",
                                "flat in vec3 v_eye_pos;\n#define u_camera_pos v_eye_pos")
    return source


DEPTH_VERTEX = """
#version 330
in vec3 in_position;
in mat4 i_model;
in vec4 i_flags;
uniform mat4 u_light_vp;
void main() {
    if (i_flags.x < 0.5) { gl_Position = vec4(0.0, 0.0, 2.0, 1.0); return; }  // not a shadower
    gl_Position = u_light_vp * (i_model * vec4(in_position, 1.0));
}
"""

DEPTH_FRAGMENT = """
#version 330
void main() {}
"""

#: Full-screen triangle; no vertex buffer needed (draw 3 vertices).
FULLSCREEN_VERTEX = """
#version 330
out vec2 v_uv;
void main() {
    vec2 p = vec2((gl_VertexID << 1) & 2, gl_VertexID & 2);
    v_uv = p;
    gl_Position = vec4(p * 2.0 - 1.0, 0.0, 1.0);
}
"""

#: Draws texture ``u_scene`` over the viewport, filtered: a frame drawn at a lower
#: resolution (Renderer.render_scale) scaled up to the output.
UPSCALE_FRAGMENT = """
#version 330
in vec2 v_uv;
uniform sampler2D u_scene;
out vec4 f_color;
void main() { f_color = texture(u_scene, v_uv); }
"""

HUD_VERTEX = """
#version 330
uniform vec4 u_rect;  // x0, y0, x1, y1 in NDC
out vec2 v_uv;
const vec2 corners[6] = vec2[6](vec2(0.0, 0.0), vec2(1.0, 0.0), vec2(1.0, 1.0),
                                vec2(0.0, 0.0), vec2(1.0, 1.0), vec2(0.0, 1.0));
void main() {
    vec2 p = corners[gl_VertexID];
    v_uv = vec2(p.x, 1.0 - p.y);  // the text image's first row is its top
    gl_Position = vec4(mix(u_rect.xy, u_rect.zw, p), 0.0, 1.0);
}
"""

HUD_FRAGMENT = """
#version 330
in vec2 v_uv;
uniform sampler2D u_text;
out vec4 f_color;
void main() { f_color = texture(u_text, v_uv); }
"""

#: Default vertex stage for a ShaderProgram that names only a fragment shader: gives the
#: user's fragment shader ``v_world``, ``v_normal``, ``v_uv`` and ``v_color``.
DEFAULT_USER_VERTEX = "#version 330" + MESH_INPUTS + """out vec3 v_world;
out vec3 v_normal;
out vec2 v_uv;
out vec4 v_color;
void main() {
    vec4 world = i_model * vec4(in_position, 1.0);
    mat3 m = mat3(i_model);
    v_world = world.xyz;
    v_normal = m * (in_normal / vec3(dot(m[0], m[0]), dot(m[1], m[1]), dot(m[2], m[2])));
    v_uv = in_uv;
    v_color = in_color * i_color;
    gl_Position = u_proj * (u_view * world);
}
"""

_LEGACY_LIGHTS = """
struct c_LightSourceParameters {
    vec4 ambient; vec4 diffuse; vec4 specular; vec4 position;
    vec3 spotDirection; float spotCutoff;
};
uniform c_LightSourceParameters c_LightSource[MAX_LIGHTS_PLACEHOLDER];
#define gl_LightSource c_LightSource
""".replace("MAX_LIGHTS_PLACEHOLDER", str(MAX_LIGHTS))

#: Prepended to a vertex shader written for the fixed-function era (no ``#version`` or a
#: version below 330), mapping its built-ins onto the engine's inputs. The author's
#: ``main`` is renamed so the engine can pass the colour and texture coordinate through.
LEGACY_VERTEX_PRELUDE = "#version 330" + MESH_INPUTS + """out vec4 c_TexCoord[2];
out vec4 c_FrontColor;
""" + _LEGACY_LIGHTS + """
#define attribute in
#define varying out
#define gl_Vertex vec4(in_position, 1.0)
#define gl_Normal in_normal
#define gl_Color (in_color * i_color)
#define gl_MultiTexCoord0 vec4(in_uv, 0.0, 1.0)
#define gl_ModelViewMatrix (u_view * i_model)
#define gl_ProjectionMatrix u_proj
#define gl_ModelViewProjectionMatrix (u_proj * u_view * i_model)
#define gl_NormalMatrix mat3(transpose(inverse(u_view * i_model)))
#define ftransform() (u_proj * u_view * i_model * vec4(in_position, 1.0))
#define gl_TexCoord c_TexCoord
#define gl_FrontColor c_FrontColor
#define main c_user_main
"""

LEGACY_VERTEX_EPILOGUE = """
#undef main
void main() {
    c_FrontColor = in_color * i_color;
    c_TexCoord[0] = vec4(in_uv, 0.0, 1.0);
    c_TexCoord[1] = vec4(0.0);
    c_user_main();
}
"""

LEGACY_FRAGMENT_PRELUDE = """#version 330
in vec4 c_TexCoord[2];
in vec4 c_FrontColor;
out vec4 c_FragColor;
""" + _LEGACY_LIGHTS + """
#define varying in
#define gl_FragColor c_FragColor
#define gl_TexCoord c_TexCoord
#define gl_Color c_FrontColor
#define texture2D texture
"""

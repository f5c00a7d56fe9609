#version 330 core
// Dear ImGui pixels: vertex colour times the font atlas texel (alpha-blended by the caller).
uniform sampler2D Texture;
in vec2 Frag_UV;
in vec4 Frag_Color;
out vec4 Out_Color;

void main() {
    Out_Color = Frag_Color * texture(Texture, Frag_UV.st);
}

#version 330 core
// The plain copy, the video controller: each window pixel of the picture shows the texel
// under its centre, nearest neighbour (the texture is exactly the picture's size, so pixel
// centres land on texel centres and nothing is filtered). blit.frag does the same with the
// loupe's magnification and the stretch after a resize; this one is what is drawn at every
// other frame. A texture fetch at an interpolated coordinate is the fragment shader llvmpipe
// runs fastest: at 1580 x 1080 on two cores, 8.7 ms of its CPU a copy against 13.3 ms for a
// texelFetch at gl_FragCoord.
uniform sampler2D frame;
in vec2 uv;
out vec4 color;

void main() {
    color = vec4(texture(frame, uv).rgb, 1.0);
}

#version 330 core
// Copies the CPU framebuffer to the screen texel for pixel: no filtering, no lighting.
// The texture holds the image in its row order (row 0 = top) and GL counts window rows from
// the bottom, so window row y shows image row H-1-y. ``origin`` is the picture's bottom-left
// corner in window pixels (the picture sits beside the panels, never under them).
// The loupe: picture pixel q (image rows, from the top) shows framebuffer pixel
// texel_anchor + floor((q - screen_anchor) / magnify), nearest neighbour (magnify 1 with both
// anchors 0 is the copy above); it only samples the finished frame.
// ``shown`` is the picture area's size: a frame of another size (the window was resized and
// the new frame is not there yet) is stretched over it, nearest neighbour: picture texel t
// shows frame texel floor(t * size / shown) (app.viewer.loupe.stretched, the same mapping).
uniform sampler2D frame;
uniform ivec2 origin;
uniform ivec2 shown;
uniform int magnify;
uniform ivec2 screen_anchor;
uniform ivec2 texel_anchor;
out vec4 color;

void main() {
    ivec2 size = textureSize(frame, 0);
    ivec2 pixel = ivec2(gl_FragCoord.xy) - origin;
    ivec2 q = ivec2(pixel.x, shown.y - 1 - pixel.y);
    ivec2 d = q - screen_anchor;
    // floor division for negative d too (GLSL's / truncates and % is undefined there); exact
    // in float for any picture size, the magnification being a power of two
    ivec2 k = ivec2(floor(vec2(d) / float(magnify)));
    ivec2 texel = magnify == 1 ? q : texel_anchor + k;
    if (shown != size && texel.x >= 0 && texel.y >= 0) {
        texel = texel * size / shown;       // whole numbers: exact, and floor for t >= 0
    }
    if (texel.x < 0 || texel.x >= size.x || texel.y < 0 || texel.y >= size.y) {
        // The window grew and the new frame is not rendered yet: show black, not garbage.
        color = vec4(0.0, 0.0, 0.0, 1.0);
        return;
    }
    color = vec4(texelFetch(frame, texel, 0).rgb, 1.0);
}

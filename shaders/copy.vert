#version 330 core
// The plain copy's rectangle: two triangles over the viewport (the picture's own area), each
// corner with its texture coordinate. Image row 0 is the texture's row 0 and the top of the
// picture (GL counts window rows from the bottom), so t runs from 1 at the bottom to 0 at the
// top. Nothing of the scene is transformed here.
in vec2 corner;     // clip space: (-1, -1) .. (1, 1)
out vec2 uv;

void main() {
    uv = vec2(0.5 * (corner.x + 1.0), 0.5 * (1.0 - corner.y));
    gl_Position = vec4(corner, 0.0, 1.0);
}

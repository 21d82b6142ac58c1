#version 330 core
// The scene's depth pre-pass (rain_core/gfx/scene_draw.py): core/scene.vert's depths only. The colour it leaves
// is overwritten by the sky, drawn over every pixel next.
void main() {
}

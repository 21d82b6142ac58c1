#version 330 core
// The scene's depth pre-pass (rain_core/gfx/scene_draw.py): core/scene.vert's depths only. The colour it leaves
// is undefined; the lit pass overwrites every such pixel (the same meshes at the same depths pass "<=").
void main() {
}

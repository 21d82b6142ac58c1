// Distance (m) along the view axis (clip w) of a window depth in [0, 1], for a perspective camera's near and far
// planes (m): the inverse of its projection's depth.
float view_distance(float window_depth, vec2 near_far) {
    float z = window_depth * 2.0 - 1.0;
    float n = near_far.x, f = near_far.y;
    return 2.0 * n * f / (f + n - z * (f - n));
}

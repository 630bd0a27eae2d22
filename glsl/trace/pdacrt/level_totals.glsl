// The eight totals of a level (next-level nodes, triangle ids, ray ids; terminal nodes,
// triangle ids, ray ids; next-level triangle and ray tiles), shared by
// level_summary.comp and level_plan.comp: each channel's exclusive sum at the last
// child plus that child's own value. The host reads these 32 bytes once per level to
// size the next level (Algorithm 1 line 11) and to decide whether the terminal-node
// buffer must be flushed first (line 7). The including kernel declares the buffers
// channels, offsets (their scan) and totals.
#ifndef SPLITRAY_LEVEL_TOTALS_GLSL
#define SPLITRAY_LEVEL_TOTALS_GLSL

void write_level_totals(uint child_count, uint stride) {
    uint last = child_count - 1u;
    for (uint k = 0u; k < CHANNELS; ++k) {
        totals.data[k] = CHANNEL_OFFSET(offsets.data, stride, k, last) + channels.data[k * stride + last];
    }
}

#endif

// For the full-screen fragment passes.

// The pixel this invocation writes: gl_FragCoord is at the pixel centre
// (x + 0.5, y + 0.5) of a viewport that starts at (0, 0), row 0 at the bottom.
ivec2 pixel_coord() { return ivec2(gl_FragCoord.xy); }

"""The compositing maths: the images Glint hands the compositor, and the node
group that turns them into the frame with reflections, described as data
(the images themselves are made in logic/group_images.py).

Before the render Glint knows the G-buffer and where each pixel's reflection
comes from, not its colour; the compositor, after the render, has the colour.
So the core computes everything that does not depend on colour and hands the
compositor two images:

    UV image     = (u, v, vis, rep)    Map UV samples the frame at (u, v) and
                                       premultiplies by vis (the trace's hit
                                       confidence x the screen-edge fade); rep:
                                       the share of the engine's specular the
                                       pixel replaces (vis, or a hidden side's)
    weight image = (W.r, W.g, W.b, lod)
                   W = F0 * A + B, the split-sum weight of the pixel's specular
                   lobe (glint_core.specular_weight: Fresnel and roughness at
                   the real view angle); lod = glint_core.cone_lod, the
                   footprint of the reflection cone as log2 of pixels

and, with *Fill Hidden Reflections*, two small ones over the box of the pixels
whose ray came into an object by its hidden side (:func:`group_images.hidden_images`):

    hidden image    = (albedo, vis)    that side's material colour, the ray's vis
                                       (the UV image's vis is then 0, rep this vis)
    hidden UV image = (u, v, 1, 1)     each box pixel's own place in the frame
                                       (third channel 0 where it is no hidden side)

and the group (:data:`GROUP_NODES` / :data:`GROUP_LINKS`) computes, per pixel,

    C   = frame(u, v) * vis + rep * albedo * frame      the reflected colour: a
                                                        hidden side lit by what
                                                        reflects it (below)
    S   = Specular Light * Specular Color               the engine's own specular
    D   = C * W - rep * S                               what changes: the engine's
                                                        specular out where a hit
                                                        replaces it, the reflection in
                                                        (under a uniform world:
                                                        C * W - min(rep * S, frame))
    D2  = D + W * vis * D(u, v)                         the second bounce (below)
    R   = D2 blurred at the pixel's lod                 (rough surfaces only)
    out = max(frame + R, 0)                             no pixel below 0

Replace, not add: where the trace found the reflection (vis 1) the engine's
specular of the world is taken out and the reflection put in; where it found
nothing (vis 0), D = 0 and the pixel is exactly the engine's. Under Eevee and
a uniform world the group's two inputs are the world's colour and the weight
image instead of the passes (S = colour x W, logic/world.py), and the group
makes S from them (``use_passes`` off): one node instead of seven, each of
which the compositor runs on every pixel.
Engines without
those passes (Workbench) leave S unlinked, 0: the reflection is added, which
is what there is to replace there (docs/addon.md, per engine).

At most the frame: under a uniform world, frame + D = max(frame - rep * S, 0)
+ C * W per channel, the core's combine with a specular base
(docs/look-core.md). That S is a model of what the engine put in, and where
the engine put in less (Eevee Legacy's ambient occlusion darkens its specular;
a metal's frame holds nothing else) taking out the whole of it left the pixel
below the reflection alone, or below 0: a black band under a metal sphere,
negative values in a written EXR. The frame is the most the engine's specular
can have been. The passes' S is what the engine put in, which the frame holds,
and Workbench's is 0: those paths take it out whole, without the three nodes.
C is read once: the minimum is taken of what leaves, not of D and C * W -
frame, which would run Map UV twice in a compositor that makes a node's output
again for each reader (3.4's, docs/frame-cost.md). The blur then spreads each
pixel's D over its neighbours, whose frames may hold less, so frame + R is
held at 0 or above after it: one node on the frame's canvas (a Mix Lighten
with black), cheaper than max(R, -frame) on the region, which takes three. It
would also raise a negative pixel of the engine's own to 0, which no engine
Glint composites on renders.

The blur: :data:`BLUR_LEVELS` Gaussian levels of D (the first Blender's 3x3
Soften filter after 4.1 and its Blur node's sampled Gaussian before, both of
which cost less there than the others, its Fast Gaussian, whose cost does not
grow with its size: host/nodes.py), blended by lod the way the core's
cone blur blends its mip levels: a pixel at lod l takes
mix(..., mix(mix(D, B1, s1), B2, s2) ...), s_j = clamp((l - lod_{j-1}) /
(lod_j - lod_{j-1}), 0, 1). A level j Gaussian (but the first, a 3x3 filter
at lod 2: :data:`SOFTEN_LOD`) holds half its energy within
a disc of diameter LEVEL_FOOTPRINT_SHARE x 2^lod_j, half the cone's footprint
(``cone_tan``; why half: at :data:`LEVEL_FOOTPRINT_SHARE`): sigma = 2^lod /
(4 sqrt(2 ln 2)). Blender's Fast Gaussian blurs with sigma = its size / 2 or
/ 3, its sampled Gaussian with sigma = its radius / 3 (host/nodes.py). Blurring D rather than C
weights each neighbour by its own W and S, which vary slowly over a rough
surface. A frame with no rough reflective surface switches the levels off
(``use_blur``): the compositor then does not run them at all.

The coarse levels: a Fast Gaussian costs the same per pixel whatever its
sigma, and the wide levels (sigma 3.4, 14 and 54 pixels) hold nothing finer
than a few pixels. So only the first level (sigma 0.71, the 3x3 filter) blurs the region's
pixels; the others blur a canvas with one texel per COARSE x COARSE block,
1/16 of the pixels, over the whole frame (group_images.coarse_size). Map UV makes it: the
coarse image's uv puts texel (i, j) at the frame's pixel (i W / cw, j H / ch),
and Map UV's filter, which sizes itself by how far the uv moves between
neighbouring texels, averages the pixels around it. The levels are mixed
there as above, by the mean lod of the blurred pixels nearest each texel, and
that mix is read back at each pixel at texel coordinates (x cw / W, y ch / H):
where the compositor places regions (3.x-4.1) by a Scale to the frame's size
(bilinear, a tenth of a Map UV's cost there; a Blur of a tenth of a pixel
before it, ``keep``, makes the mix once instead of once per texel read), and
moved into the region; elsewhere by a second Map UV (the fine image's uv).
Past the last texel the Scale blends with 0: the wide levels fade over the
last 4 pixels of the frame's right and top edges. Since the mixing weights
rise in order (s_j > 0 only where s_{j-1} = 1), the chain
mix(mix(mix(D, B1, s1), B2, s2), ...) equals mix(mix(D, B1, s1), Q, s2) with Q
the coarse mix of B2..B4: exact up to a texel's lod standing for its pixels'.
The texels lie on the frame's grid, so a region reads the same canvas as the
whole frame. Measured in docs/frame-cost.md (*The coarse levels*, *The coarse
levels read back by a Scale*).

Hidden sides: a ray that comes into an object by the side the camera does not
see (a floor's ray meeting a sphere's underside) has no pixel of the frame to
show. The back layer says which surface it is, the material table its albedo;
its light is guessed as what reflects it: the surface faces the reflector it is
seen in (the floor under the sphere), so what lights it is that reflector's
own radiance, the frame at the pixel itself. Albedo x frame is then the diffuse
light of a surface that sees nothing but the reflector, its colour right next
to a contact and too bright where the reflector is far or small (docs/addon.md,
*Hidden sides*). Those pixels are few (contact bands, a floating object's edge),
and the compositor's cost is per pixel of a canvas, so the term is made on their
own box: Map UV reads the frame at each box pixel's own uv (all of them move
one pixel per pixel, so its filter stays a pixel wide), a Multiply by the albedo,
a Translate into the region by the offset image's last two channels, and one
region-sized Add by rep. The Add's factor gates it: a cleared UV image (rep 0)
passes the frame through whatever the hidden images hold. A Switch
(``use_hidden``) leaves the nodes out when *Fill Hidden Reflections* is off.

The second bounce: a mirror that reflects another mirror shows that mirror as
the engine rendered it, without its reflection. Sampling the frame *with* the
first bounce at (u, v) adds it: frame + D at the hit, so C' = C + vis D(u, v)
and the pixel's change gains W * vis * D(u, v) (one more Map UV, of D). It
reflects D unblurred, and the hit's own hit is not followed further. It costs
what the first Map UV costs (the group's largest node), so it runs only where
reflectors can see each other (``use_bounce``, see :func:`use_second_bounce`).

The region: D is 0 wherever vis is 0, and R differs from D only where lod > 0,
so the frame changes only inside the bounding box of those pixels
(:func:`group_images.image_region`). The uv and weight images are cut to it, and the whole
of R is computed on that many pixels: both Map UVs, D on either path, the
bounce and the blur levels (Blender sizes an operation by its inputs; Map UV
costs about 100 ns per pixel of its uv input, hit or not, a Fast Gaussian level
about 220 ns per pixel of its canvas). D is 0 on the region's border (the pad
has no hit), so the levels see what they would on the frame, up to how
Blender's recursive Gaussian treats a canvas edge a few sigma away (4e-4 at
most, tests/blender/test_region.py). Blender centres a smaller canvas on the
frame; a Translate by the offset that a 1x1 image holds (:func:`group_images.region_offset`)
puts R in its place before it meets the frame. The engine's frame-sized S goes
the other way: a Translate by minus the offset brings the region's pixels to
the frame's centre, where the region-sized operation that takes it (C * W
first, so the region sizes it) reads them. The offset is an image, not a node
value, because the render composites with a copy of the tree taken before
Glint knows the frame's region. A debug view or the layers EXR wants the whole
frame's uv: the region is then the whole frame, and the offset 0.

The tests run the same description on numpy arrays (tests/addon/group_model.py)
to check the wiring against the formula without Blender; that model sizes each
operation by its inputs, as Blender does, and raises where a region meets the
frame untranslated.
"""
from __future__ import annotations

import math
from typing import Dict, List, Optional, Tuple

# Image data-blocks the group reads (filled by the add-on before compositing).
IMAGE_UV = "Glint UV"
IMAGE_WEIGHT = "Glint Weight"
IMAGE_DEBUG = "Glint Debug"
IMAGE_POSITION = "Glint Position"
IMAGE_NORMAL = "Glint Normal"
IMAGE_SPECULAR = "Glint Specular"
IMAGE_OFFSET = "Glint Offset"  # 1x1: where the region's images go in the frame, and where the hidden
# sides' box goes in the region (group_images.region_offset, group_images.hidden_images)
IMAGE_COARSE = "Glint Coarse"  # the coarse canvas of the wide blur levels (:func:`group_images.coarse_images`)
IMAGE_FINE = "Glint Fine"      # where each region pixel reads the coarse canvas
IMAGE_HIDDEN = "Glint Hidden"  # (albedo, vis) of the hidden sides rays come into, on their box
ALL_IMAGES = (IMAGE_UV, IMAGE_WEIGHT, IMAGE_DEBUG, IMAGE_POSITION, IMAGE_NORMAL, IMAGE_SPECULAR, IMAGE_OFFSET,
              IMAGE_COARSE, IMAGE_FINE, IMAGE_HIDDEN)
# The images cut to the frame's region (the others stay frame-sized, or, the
# hidden sides', their own box inside it).
REGION_IMAGES = (IMAGE_UV, IMAGE_WEIGHT, IMAGE_FINE)
# The one image whose zeros make the group pass the frame through (vis = 0:
# C = 0 and D = 0): what a frame Glint does not handle clears.
PASS_THROUGH_IMAGE = IMAGE_UV
# Images earlier versions of the group read; removed with Glint's own.
LEGACY_IMAGES = ("Glint Mask", "Glint Hidden UV")

# Engines that trace reflections themselves: Glint leaves their frame as it is
# (a screen-space guess can only be worse than a path-traced reflection).
TRUE_REFLECTION_ENGINES = ("CYCLES",)
TRUE_REFLECTION_NOTE = ("Cycles traces true reflections: the frame is left as Cycles rendered it "
                        "(Glint replaces the specular of rasterizing engines: Eevee, Workbench)")

GROUP_NAME = "Glint"
GROUP_NODE_NAME = "Glint"  # the group node in the scene's compositor tree
EXR_NODE_NAME = "Glint EXR"
# Beside the group, for Eevee under a uniform world (logic/world.py): S = the
# world's colour (an RGB node into Specular Light) x W (the weight image into
# Specular Color), instead of Eevee's passes.
WORLD_COLOUR_NODE = "Glint World Colour"
WORLD_WEIGHT_NODE = "Glint World Weight"

GROUP_INPUTS = (
    ("Image", "NodeSocketColor"),
    ("Specular Light", "NodeSocketColor"),  # the engine's specular radiance (Eevee: Specular Light)
    ("Specular Color", "NodeSocketColor"),  # its weight (Eevee: Specular Color)
)
# The passes that feed GROUP_INPUTS[1:] (host/nodes.PASS_OUTPUTS names their
# Render Layers outputs in each Blender), and the view layer flags that make
# the engine write them. Eevee's Specular Light / Color passes are its glossy
# ones in the API.
ENGINE_PASSES = (("glossy_direct", "Specular Light", "use_pass_glossy_direct"),
                 ("glossy_color", "Specular Color", "use_pass_glossy_color"))
GROUP_OUTPUTS = (
    ("Image", "NodeSocketColor"),  # composited (or the debug view)
    ("Reflection", "NodeSocketColor"),  # R: what Glint changes (rgb may be negative), alpha = vis
    ("Base", "NodeSocketColor"),
    ("UV", "NodeSocketColor"),
    ("Visibility", "NodeSocketFloat"),
    ("Position", "NodeSocketColor"),
    ("Normal", "NodeSocketColor"),
    ("Specular", "NodeSocketColor"),
    ("Engine Specular", "NodeSocketColor"),  # S: the engine's specular, where a hit replaces it
)

# Debug views: enum value -> (label, description). REFLECTION is computed in the
# compositor; the others are G-buffer layers shown through IMAGE_DEBUG.
DEBUG_VIEWS = (
    ("NONE", "None", "The composited frame"),
    ("POSITION", "Position", "View-space position (x, y, z)"),
    ("NORMAL", "Normal", "View-space normal, shown as n * 0.5 + 0.5"),
    ("SPECULAR", "Specular", "Specular colour (rgb) of the specular buffer"),
    ("UV", "Reflected UV", "The reflected uv (u, v, 0) where a reflection was found"),
    ("VISIBILITY", "Visibility", "The reflection's visibility as grey"),
    ("REFLECTION", "Reflection", "What Glint changes in the frame: the reflection in, the engine's "
                                 "own specular out where it is replaced"),
)
GBUFFER_DEBUG_VIEWS = ("POSITION", "NORMAL", "SPECULAR", "UV", "VISIBILITY")

# The blur levels: (lod, sigma in pixels). Every second lod up to 2^8 = 256
# pixels: the footprint of a roughness 0.5 lobe 240 pixels from its hit.
# A level's Gaussian holds half its energy within a disc of diameter
# LEVEL_FOOTPRINT_SHARE x 2^lod. The cone's own half-energy disc is the whole
# footprint (share 1), but a Gaussian that wide spreads the GGX lobe's narrow
# core as far as its long tail: against Cycles (bench/look_compare.py, 3.4)
# share 1 gave error 0.26 on the rough floor and 0.19 on the metal sphere,
# share 0.5 gave 0.23 and 0.16 (docs/frame-cost.md, *The coarse levels*).
HALF_ENERGY_SIGMA = 1.0 / (2.0 * math.sqrt(2.0 * math.log(2.0)))
LEVEL_FOOTPRINT_SHARE = 0.5
# The first level is Blender's Filter node, Soften: the 3x3 binomial kernel
# (1 2 1)^T (1 2 1) / 16, whose variance is 1/2 along each axis, at a quarter
# of a Fast Gaussian's cost on 5.2 (docs/frame-cost.md, *The first level as a 3x3
# filter*). It keeps the Fast Gaussian's place at lod 2, where the rule above
# asks for sigma 0.85: placed at its own lod by the rule (1.74) it blurred the
# pixels between the two more, and look_compare's metal sphere moved away from
# Cycles (error 0.157 -> 0.159 on 3.4, 0.194 -> 0.198 on 5.2); at lod 2 every
# scene is within 0.002 of the Fast Gaussian's figures and the metal sphere
# closer (0.153, 0.192).
SOFTEN_SIGMA = math.sqrt(0.5)
SOFTEN_TAPS = (0.25, 0.5, 0.25)  # the kernel along each axis; the 3x3 kernel is their outer product
# Blender's Filter node clamps its result at 0 (3.4 to 5.2 alike), and D is
# negative wherever the reflection darkens the frame. The kernel sums to 1, so
# it filters D + SOFTEN_LIFT and the lift is taken off again: exact while
# D > -SOFTEN_LIFT (an engine specular 256 times the frame's white being
# replaced), at a rounding of 2^-15 (3e-5, below an 8-bit step of the darkest
# sRGB grey).
SOFTEN_LIFT = 256.0
SOFTEN_LOD = 2.0
BLUR_LEVELS = ((SOFTEN_LOD, SOFTEN_SIGMA),) + tuple(
    (float(lod), HALF_ENERGY_SIGMA * LEVEL_FOOTPRINT_SHARE * 2.0 ** lod) for lod in (4, 6, 8))
# The first FULL_LEVELS levels blur the region's pixels; the wider ones a
# canvas with one texel per COARSE x COARSE block of the frame's pixels
# ("The coarse levels" above). Level 2's sigma is 3.4 pixels, 0.85 texels.
FULL_LEVELS = 1
FIRST_COARSE = FULL_LEVELS + 1  # the level whose mix brings the coarse canvas back
COARSE = 4


def _blur_node(sigma: float):
    return ("blur", {"sigma": sigma}, {})


def _mix(blend: str, defaults=None):
    return ("mix", {"blend": blend}, defaults or {})


def _translate(sign: int = 1, onto: str = "frame"):
    """A Translate by the region's offset (sign 1: a region-sized canvas to its
    place in the frame) or by minus it (sign -1: the frame moved so that the
    region's pixels lie where a region-sized canvas centred on it reads them);
    ``onto="region"``: by the hidden box's offset, the box's canvas to its place
    in the region (the offset image's last two channels); ``onto="box"``: the
    frame moved by minus the box's offset in the frame, so that a box-sized
    operation reads the frame's pixels under the box; ``onto="grid"``: the
    coarse canvas stretched to the frame, moved by :func:`group_images.coarse_grid_shift`,
    the node's own values, which the add-on writes per frame where the host
    needs them (host/nodes.scale_reads_by_domain) and mutes the node elsewhere;
    read bilinearly. There it makes the host's Scale read as ``frame_scale``
    does alone, so this model passes the canvas through."""
    return ("translate", {"sign": sign, "onto": onto}, {})


def _separate():
    return ("separate", {}, {})


def _math(operation: str, clamp: bool, defaults):
    return ("math", {"operation": operation, "clamp": clamp}, defaults)


# Node description: name -> (kind, options, {input index: default value}).
# Kinds are abstract (image, map_uv, separate, combine, translate, mix, math,
# switch, blur, soften, frame_scale, keep): host/nodes.py lowers each onto the
# node type and options of the running Blender (soften: the 3x3 Filter, or a
# sampled Gaussian of its sigma, host/nodes.soften_is_a_filter; frame_scale:
# the Scale node to the render size, stretched; keep: the image unchanged, made
# once, host/nodes.KEEP_RADIUS). Inputs are numbered as the kind defines them,
# whatever the host calls its sockets: mix (factor, a, b), math (a, b, c),
# switch (off, on), translate (image, x, y), map_uv (image, uv), blur (image),
# soften (image), frame_scale (image), keep (image), combine (r, g, b, a);
# separate's outputs are (r, g, b, a).
GROUP_NODES: Dict[str, Tuple[str, Dict[str, object], Dict[int, object]]] = {
    "uv_image": ("image", {"image": IMAGE_UV}, {}),
    "weight_image": ("image", {"image": IMAGE_WEIGHT}, {}),
    "debug_image": ("image", {"image": IMAGE_DEBUG}, {}),
    "position_image": ("image", {"image": IMAGE_POSITION}, {}),
    "normal_image": ("image", {"image": IMAGE_NORMAL}, {}),
    "specular_image": ("image", {"image": IMAGE_SPECULAR}, {}),
    # alpha = 0: no fading by uv derivatives, so Map UV only premultiplies by vis.
    "map_uv": ("map_uv", {}, {}),
    "sep_uv": _separate(),
    "offset_image": ("image", {"image": IMAGE_OFFSET}, {}),
    "sep_offset": _separate(),
    # The offset the other way, for the engine's frame-sized specular S: moved
    # by minus the offset, the frame's region lies at its centre, where a
    # region-sized operation reads a larger input (Blender centres it).
    "offset_back_x": _math("MULTIPLY", False, {1: -1.0}),
    "offset_back_y": _math("MULTIPLY", False, {1: -1.0}),
    # The region's result into the frame (see "The region" above), and S and D
    # between the two sizes.
    "reflection_to_frame": _translate(),
    "delta_to_frame": _translate(),
    "specular_to_region": _translate(-1),
    "sep_weight": _separate(),  # the weight image's alpha: the pixel's lod
    # Hidden sides: C + rep * albedo * frame (see "Hidden sides" above), made
    # on the hidden pixels' box and moved into the region.
    "hidden_image": ("image", {"image": IMAGE_HIDDEN}, {}),
    # The frame moved by minus the box's offset in the frame (the region's plus
    # the box's in the region), so that the box-sized Multiply reads the
    # frame's pixels under the box: the light at each hidden pixel, read in
    # whole pixels (a whole-frame group moves it by 0).
    "box_back_x": _math("SUBTRACT", False, {}),
    "box_back_y": _math("SUBTRACT", False, {}),
    "hidden_light": _translate(-1, onto="box"),
    "hidden_colour": _mix("MULTIPLY", {0: 1.0}),   # albedo * frame
    "hidden_to_region": _translate(1, onto="region"),
    "with_hidden": _mix("ADD"),                    # C + rep * albedo * frame
    "use_hidden": ("switch", {"on": True}, {}),
    # D on a frame-sized canvas, 0 x frame + 1 x D: what the second Map UV
    # samples (it scales uv by its image's size).
    "bounce_source": _mix("MIX", {0: 1.0}),
    "weighted": _mix("MULTIPLY", {0: 1.0}),        # C * W
    "engine_specular": _mix("MULTIPLY", {0: 1.0}),  # S = light * colour
    # Eevee writes its light passes divided by their colour: where the colour is
    # 0 the light is inf or NaN and S NaN, which vis * S = 0 * NaN would carry
    # into the frame. max(x, 0) per channel (Blender's MAXIMUM returns its
    # second input when the first is NaN) makes S 0 there and nothing else.
    "sep_specular": _separate(),
    "finite_r": _math("MAXIMUM", False, {1: 0.0}),
    "finite_g": _math("MAXIMUM", False, {1: 0.0}),
    "finite_b": _math("MAXIMUM", False, {1: 0.0}),
    "finite_specular": ("combine", {}, {3: 1.0}),
    "delta": _mix("SUBTRACT"),                      # C * W - rep * S
    # Under a uniform world S = colour x W, a model of what the engine put in:
    # taken out at most the frame (see "At most the frame" above), the frame
    # read on the region's pixels. Each operation's first image input is
    # region-sized, so the region sizes it; C is read once.
    "world_specular": _mix("MULTIPLY", {0: 1.0}),     # W * colour
    "replaced_specular": _mix("MULTIPLY", {0: 1.0}),  # rep * W * colour
    "frame_to_region": _translate(-1),
    "taken_out": _mix("DARKEN", {0: 1.0}),             # min(rep * W * colour, frame)
    "world_delta": _mix("SUBTRACT", {0: 1.0}),         # C * W - min(rep * W * colour, frame)
    "use_passes": ("switch", {"on": True}, {}),
    # D made once where the compositor would make it again for each node that
    # reads it (3.x-4.1's Tiled compositor: the first level's blur, the coarse
    # canvas's Map UV, the first mix and, with the bounce, its source each
    # evaluate the chain behind D anew); after 4.1 each node is one pass anyway.
    "d_kept": ("keep", {}, {}),
    "d_buffered": ("switch", {"on": False}, {}),
    "bounce_map_uv": ("map_uv", {}, {}),  # vis * D(u, v)
    "bounce_weighted": _mix("MULTIPLY", {0: 1.0}),  # W * vis * D(u, v)
    "bounced": _mix("ADD", {0: 1.0}),               # D2 = D + W * vis * D(u, v)
    "use_bounce": ("switch", {"on": False}, {}),
    "use_blur": ("switch", {"on": True}, {}),
    "combined": _mix("ADD", {0: 1.0}),              # frame + R
    # no pixel below 0 after the blur (see "At most the frame" above)
    "non_negative": _mix("LIGHTEN", {0: 1.0, 2: (0.0, 0.0, 0.0, 1.0)}),
    "show_reflection": ("switch", {"on": False}, {}),
    "show_debug": ("switch", {"on": False}, {}),
}
# The wide levels blur a coarse copy of D2 (see "The coarse levels" above):
# Map UV reads D2 at the coarse texels' centres (the coarse image's uv; the
# filter averages the COARSE x COARSE pixels each covers), the levels blur it
# at sigma / COARSE and are mixed there by the coarse lod, and one more Map UV
# (the fine image's uv) brings that mix back to the region's pixels.
GROUP_NODES.update({
    "coarse_image": ("image", {"image": IMAGE_COARSE}, {}),
    "fine_image": ("image", {"image": IMAGE_FINE}, {}),
    "sep_coarse": _separate(),  # the coarse image's alpha: the coarse texel's lod
    # averaging its footprint (a texel's 4x4 pixels), where a host lets Map UV
    # choose: 5.0's offers a bilinear read, the default, which would take one
    # pixel of the 16
    "to_coarse": ("map_uv", {"footprint": True}, {}),
    "from_coarse": ("map_uv", {}, {}),
    # The read-back where the host's Scale reads as frame_scale (3.x-4.1, and
    # 5.x with coarse_grid: host/nodes.coarse_read_back_by_scale): the coarse
    # canvas stretched to the frame (a bilinear read per pixel, a tenth of a
    # Map UV's cost on 3.4), then the frame's region taken out; the fine image
    # is then not read (switch_states()).
    "coarse_kept": ("keep", {}, {}),
    "coarse_to_frame": ("frame_scale", {}, {}),
    "coarse_to_region": _translate(-1),
    # after it, as the last transform a 5.x Scale's read takes: group_images.coarse_grid_shift
    "coarse_grid": ("translate", {"sign": 1, "onto": "grid"}, {1: 0.0, 2: 0.0}),
    "coarse_by_scale": ("switch", {"on": False}, {}),
})
for _j, (_lod, _sigma) in enumerate(BLUR_LEVELS, start=1):
    _lo = BLUR_LEVELS[_j - 2][0] if _j > 1 else 0.0
    _coarse = _j > FULL_LEVELS
    if _j == 1:  # the 3x3 filter; the sigma is for the hosts that run it as a Gaussian
        GROUP_NODES[f"blur_{_j}"] = ("soften", {"sigma": _sigma}, {})
    else:
        GROUP_NODES[f"blur_{_j}"] = _blur_node(_sigma / COARSE if _coarse else _sigma)
    # s_j = clamp(lod / (lod_j - lod_{j-1}) - lod_{j-1} / (lod_j - lod_{j-1}), 0, 1)
    _factor = _math("MULTIPLY_ADD", True, {1: 1.0 / (_lod - _lo), 2: -_lo / (_lod - _lo)})
    if GROUP_NODES[f"blur_{_j}"][0] == "soften":
        # D + lift through the filter, minus lift; the Switches take the lift's
        # mixes out where the host runs the level as a Gaussian, which does not
        # clamp (and, at the canvas's edge, would not keep a constant).
        _lift = (SOFTEN_LIFT, SOFTEN_LIFT, SOFTEN_LIFT, 1.0)
        GROUP_NODES[f"lift_{_j}"] = _mix("ADD", {0: 1.0, 2: _lift})
        GROUP_NODES[f"drop_{_j}"] = _mix("SUBTRACT", {0: 1.0, 2: _lift})
        GROUP_NODES[f"lift_in_{_j}"] = ("switch", {"on": True}, {})
        GROUP_NODES[f"lift_out_{_j}"] = ("switch", {"on": True}, {})
    if _j <= FIRST_COARSE:  # mixed on the region's pixels
        GROUP_NODES[f"level_{_j}"] = _factor
        GROUP_NODES[f"mix_{_j}"] = _mix("MIX")
    else:  # mixed on the coarse canvas, by the coarse lod
        GROUP_NODES[f"coarse_level_{_j}"] = _factor
        GROUP_NODES[f"coarse_mix_{_j}"] = _mix("MIX")
LAST_MIX = f"mix_{FIRST_COARSE}"  # the blurred D2 on the region's pixels
# The Switches that route the first level through the lift (SOFTEN_LIFT): on
# where that level is the 3x3 filter (switch_states()).
SOFTEN_LIFT_SWITCHES = tuple(name for name in GROUP_NODES if name.startswith(("lift_in_", "lift_out_")))

GROUP_IN = "__input__"
GROUP_OUT = "__output__"

# (from node, output index, to node, input index); the group's input and output
# are GROUP_IN / GROUP_OUT with socket indices into GROUP_INPUTS / GROUP_OUTPUTS.
GROUP_LINKS: List[Tuple[str, int, str, int]] = [
    (GROUP_IN, 0, "map_uv", 0),
    ("uv_image", 0, "map_uv", 1),
    ("uv_image", 0, "sep_uv", 0),
    ("offset_image", 0, "sep_offset", 0),
    ("weight_image", 0, "sep_weight", 0),
    ("sep_offset", 0, "offset_back_x", 0),
    ("sep_offset", 1, "offset_back_y", 0),
    ("offset_back_x", 0, "box_back_x", 0),
    ("sep_offset", 2, "box_back_x", 1),
    ("offset_back_y", 0, "box_back_y", 0),
    ("sep_offset", 3, "box_back_y", 1),
    (GROUP_IN, 0, "hidden_light", 0),
    ("hidden_image", 0, "hidden_colour", 1),
    ("hidden_light", 0, "hidden_colour", 2),
    ("hidden_colour", 0, "hidden_to_region", 0),
    ("sep_uv", 3, "with_hidden", 0),
    ("map_uv", 0, "with_hidden", 1),
    ("hidden_to_region", 0, "with_hidden", 2),
    # input 0 when off: C alone, the hidden sides' nodes not run
    ("map_uv", 0, "use_hidden", 0),
    ("with_hidden", 0, "use_hidden", 1),
    ("use_hidden", 0, "weighted", 1),
    ("weight_image", 0, "weighted", 2),
    (GROUP_IN, 1, "engine_specular", 1),
    (GROUP_IN, 2, "engine_specular", 2),
    ("engine_specular", 0, "sep_specular", 0),
    ("sep_specular", 0, "finite_r", 0),
    ("sep_specular", 1, "finite_g", 0),
    ("sep_specular", 2, "finite_b", 0),
    ("finite_r", 0, "finite_specular", 0),
    ("finite_g", 0, "finite_specular", 1),
    ("finite_b", 0, "finite_specular", 2),
    # the passes' path: the frame-sized S is read on the region (C * W first,
    # so the region sizes the operation); the frame holds all of the engine's
    # own specular, so it is taken out whole
    ("finite_specular", 0, "specular_to_region", 0),
    ("sep_uv", 3, "delta", 0),
    ("weighted", 0, "delta", 1),
    ("specular_to_region", 0, "delta", 2),
    # the world's path
    ("weight_image", 0, "world_specular", 1),
    (GROUP_IN, 1, "world_specular", 2),
    ("sep_uv", 3, "replaced_specular", 1),
    ("world_specular", 0, "replaced_specular", 2),
    (GROUP_IN, 0, "frame_to_region", 0),
    ("replaced_specular", 0, "taken_out", 1),
    ("frame_to_region", 0, "taken_out", 2),
    ("weighted", 0, "world_delta", 1),
    ("taken_out", 0, "world_delta", 2),
    # input 0 when off: the world's path, the passes' nodes not run
    ("world_delta", 0, "use_passes", 0),
    ("delta", 0, "use_passes", 1),
    # input 0 when off: D as it is; on: D made once (d_kept)
    ("use_passes", 0, "d_kept", 0),
    ("use_passes", 0, "d_buffered", 0),
    ("d_kept", 0, "d_buffered", 1),
    ("d_buffered", 0, "delta_to_frame", 0),
    (GROUP_IN, 0, "bounce_source", 1),
    ("delta_to_frame", 0, "bounce_source", 2),
    ("bounce_source", 0, "bounce_map_uv", 0),
    ("uv_image", 0, "bounce_map_uv", 1),
    ("bounce_map_uv", 0, "bounce_weighted", 1),
    ("weight_image", 0, "bounce_weighted", 2),
    ("d_buffered", 0, "bounced", 1),
    ("bounce_weighted", 0, "bounced", 2),
    # input 0 when off: D alone, the second Map UV not run
    ("d_buffered", 0, "use_bounce", 0),
    ("bounced", 0, "use_bounce", 1),
]
# every Translate moves by the region's offset or by minus it (the coarse grid's by its own values)
for _t, (_kind, _props, _) in GROUP_NODES.items():
    if _kind != "translate":
        continue
    if _props["onto"] == "region":
        GROUP_LINKS += [("sep_offset", 2, _t, 1), ("sep_offset", 3, _t, 2)]
    elif _props["onto"] == "box":
        GROUP_LINKS += [("box_back_x", 0, _t, 1), ("box_back_y", 0, _t, 2)]
    elif _props["onto"] == "grid":
        pass  # single values of its own (a 5.x Translate ignores a move read from an image)
    elif _props["sign"] > 0:
        GROUP_LINKS += [("sep_offset", 0, _t, 1), ("sep_offset", 1, _t, 2)]
    else:
        GROUP_LINKS += [("offset_back_x", 0, _t, 1), ("offset_back_y", 0, _t, 2)]


def _level_out(j: int) -> str:
    """The node whose output is blur level j."""
    return f"lift_out_{j}" if f"lift_out_{j}" in GROUP_NODES else f"blur_{j}"


# the blur levels work on the region: D2 is 0 on its border (the pad has no hit)
GROUP_LINKS += [
    ("coarse_image", 0, "sep_coarse", 0),
    ("use_bounce", 0, "to_coarse", 0),
    ("coarse_image", 0, "to_coarse", 1),
    ("fine_image", 0, "from_coarse", 1),
]
for _j in range(1, len(BLUR_LEVELS) + 1):
    _source = "to_coarse" if _j >= FIRST_COARSE else "use_bounce"
    if f"lift_{_j}" in GROUP_NODES:  # the filter's lift and drop around it (SOFTEN_LIFT)
        GROUP_LINKS += [(_source, 0, f"lift_{_j}", 1), (_source, 0, f"lift_in_{_j}", 0),
                        (f"lift_{_j}", 0, f"lift_in_{_j}", 1), (f"lift_in_{_j}", 0, f"blur_{_j}", 0),
                        (f"blur_{_j}", 0, f"drop_{_j}", 1), (f"blur_{_j}", 0, f"lift_out_{_j}", 0),
                        (f"drop_{_j}", 0, f"lift_out_{_j}", 1)]
    else:
        GROUP_LINKS.append((_source, 0, f"blur_{_j}", 0))
    if _j <= FIRST_COARSE:
        _below = "use_bounce" if _j == 1 else f"mix_{_j - 1}"
        GROUP_LINKS += [
            ("sep_weight", 3, f"level_{_j}", 0),
            (f"level_{_j}", 0, f"mix_{_j}", 0),
            (_below, 0, f"mix_{_j}", 1),
            ("coarse_by_scale" if _j == FIRST_COARSE else _level_out(_j), 0, f"mix_{_j}", 2),
        ]
    else:
        _below = _level_out(_j - 1) if _j == FIRST_COARSE + 1 else f"coarse_mix_{_j - 1}"
        GROUP_LINKS += [
            ("sep_coarse", 3, f"coarse_level_{_j}", 0),
            (f"coarse_level_{_j}", 0, f"coarse_mix_{_j}", 0),
            (_below, 0, f"coarse_mix_{_j}", 1),
            (_level_out(_j), 0, f"coarse_mix_{_j}", 2),
        ]
_last = len(BLUR_LEVELS)
_coarse_out = f"coarse_mix_{_last}" if _last > FIRST_COARSE else _level_out(_last)
GROUP_LINKS += [
    (_coarse_out, 0, "from_coarse", 0),
    (_coarse_out, 0, "coarse_kept", 0),
    ("coarse_kept", 0, "coarse_to_frame", 0),
    ("coarse_to_frame", 0, "coarse_to_region", 0),  # moved by minus the offset (above)
    ("coarse_to_region", 0, "coarse_grid", 0),
    # input 0 when off: the fine image's Map UV
    ("from_coarse", 0, "coarse_by_scale", 0),
    ("coarse_grid", 0, "coarse_by_scale", 1),
]
GROUP_LINKS += [
    # the Switch takes input 0 when off: the unblurred D2, levels not run
    ("use_bounce", 0, "use_blur", 0),
    (LAST_MIX, 0, "use_blur", 1),
    ("use_blur", 0, "reflection_to_frame", 0),
    (GROUP_IN, 0, "combined", 1),
    ("reflection_to_frame", 0, "combined", 2),
    # output switches: composited / reflection / G-buffer debug image
    ("combined", 0, "non_negative", 1),
    ("non_negative", 0, "show_reflection", 0),
    ("reflection_to_frame", 0, "show_reflection", 1),
    ("show_reflection", 0, "show_debug", 0),
    ("debug_image", 0, "show_debug", 1),
    ("show_debug", 0, GROUP_OUT, 0),
    ("reflection_to_frame", 0, GROUP_OUT, 1),
    (GROUP_IN, 0, GROUP_OUT, 2),
    ("uv_image", 0, GROUP_OUT, 3),
    ("sep_uv", 2, GROUP_OUT, 4),
    ("position_image", 0, GROUP_OUT, 5),
    ("normal_image", 0, GROUP_OUT, 6),
    ("specular_image", 0, GROUP_OUT, 7),
    ("finite_specular", 0, GROUP_OUT, 8),
]

# Layers of the multilayer EXR written beside the output: slot name -> group output.
EXR_LAYERS = (
    ("Image", "Image"),
    ("Base", "Base"),
    ("Reflection", "Reflection"),
    ("Position", "Position"),
    ("Normal", "Normal"),
    ("Specular", "Specular"),
    ("UV", "UV"),
    ("Visibility", "Visibility"),
    ("EngineSpecular", "Engine Specular"),
)


def switch_states(debug_view: str, use_blur: bool = True, use_bounce: bool = False,
                  world_specular: bool = False, use_hidden: bool = False,
                  soften_filters: bool = True, whole_frame: bool = False,
                  scale_read_back: Optional[bool] = None) -> Dict[str, bool]:
    """The Switch nodes' ``check`` for a debug view, whether any reflective
    surface in the frame is rough, whether the second bounce runs, whether
    S is the world colour (Specular Light) times W (``world_specular``: the
    group's Specular Color input is then not read), whether hidden sides are
    shown (``use_hidden``: the add-on then fills the hidden image every frame)
    whether the first blur level is the 3x3 filter, which needs the lift
    (``soften_filters``: host/nodes.soften_is_a_filter), and whether the group
    works on the whole frame (``whole_frame``: a compositor that cannot place a
    region, host/nodes.compositor_places_regions), where D is not copied into
    a buffer (elsewhere, ``d_kept``), and whether the coarse levels come back
    through ``frame_scale`` (``scale_read_back``:
    host/nodes.coarse_read_back_by_scale; by default where regions are placed)
    or through the fine image's Map UV."""
    if scale_read_back is None:
        scale_read_back = not whole_frame
    states = {"show_reflection": debug_view == "REFLECTION", "show_debug": debug_view in GBUFFER_DEBUG_VIEWS,
              "use_blur": bool(use_blur), "use_bounce": bool(use_bounce), "use_passes": not world_specular,
              "use_hidden": bool(use_hidden),
              "coarse_by_scale": bool(scale_read_back), "d_buffered": not whole_frame}
    states.update((name, bool(soften_filters)) for name in SOFTEN_LIFT_SWITCHES)
    return states


def dead_nodes(states: Dict[str, bool]) -> frozenset:
    """The group's nodes whose every path to an output of the group runs into
    the side of a Switch that ``states`` (:func:`switch_states`) does not pass.

    The add-on mutes them. Blender 5.x's compositor evaluates both inputs of a
    Switch, the side it drops included, so without the mute the second
    bounce's Map UV and the other read-back of the coarse levels ran on every
    frame that did not use them (docs/frame-cost.md, *Both sides of a Switch*); a
    muted node passes its first input through and computes nothing. 3.4's
    and 4.3's compositors skip the dropped side themselves, so there the mute
    changes nothing. Every output of the group counts, not only the frame's:
    a user may wire the others (the layers EXR does)."""
    incoming: Dict[str, List[Tuple[str, int]]] = {}
    for src, _, dst, di in GROUP_LINKS:
        incoming.setdefault(dst, []).append((src, di))
    live = set()
    todo = [GROUP_OUT]
    while todo:
        node = todo.pop()
        for src, di in incoming.get(node, ()):
            if node in states and GROUP_NODES[node][0] == "switch" and di != (1 if states[node] else 0):
                continue  # the side this Switch drops
            if src != GROUP_IN and src not in live:
                live.add(src)
                todo.append(src)
    return frozenset(name for name in GROUP_NODES if name not in live)


# The second bounce setting: enum value -> (label, description).
SECOND_BOUNCE = (
    ("AUTO", "Auto", "When the scene has two or more sharp or metallic reflectors, which can show each "
                     "other's reflections (rough dielectrics, such as Blender's default material, do not count; "
                     "a single concave reflector, such as a room made as one mesh, needs On)"),
    ("ON", "On", "Always: mirrors show the reflections in the mirrors they reflect; costs one more "
                 "Map UV in the compositor"),
    ("OFF", "Off", "Never: a reflected mirror shows as the engine rendered it"),
)


# A reflector counts for Auto's second bounce when its own reflection is sharp
# (alpha 1, a mirror, or above it, the gloss range: roughness below 0.25) or
# strong (a specular amount of a metal's order). A rough dielectric (Blender's default material: Roughness 0.5,
# F0 0.04) shows a faint, blurred reflection; the same reflection again inside
# another mirror is work nobody sees. Measured on look_compare's `default` scene
# (docs/look.md): counting them ran the bounce and gave error 0.33, not counting
# them 0.31, against Cycles.
BOUNCE_AMOUNT_WHEN_ROUGH = 0.5


def counts_for_second_bounce(reflective: bool, alpha: float, amount: float) -> bool:
    """Whether a reflector's material makes it count for Auto's second bounce."""
    return bool(reflective) and (alpha >= 1.0 or amount >= BOUNCE_AMOUNT_WHEN_ROUGH)


def use_second_bounce(mode: str, reflective_objects: int) -> bool:
    """Whether the group runs the second bounce, given how many objects count for
    it (:func:`counts_for_second_bounce`). One convex reflector cannot see
    itself, so Auto waits for a second one."""
    if mode not in {m for m, _, _ in SECOND_BOUNCE}:
        raise ValueError(f"second bounce: expected one of {[m for m, _, _ in SECOND_BOUNCE]}, got {mode!r}")
    return mode == "ON" or (mode == "AUTO" and reflective_objects >= 2)

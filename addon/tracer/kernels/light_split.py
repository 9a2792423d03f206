"""Light passes and clamping: a camera path's radiance split by where its light was gathered, as Cycles splits it.

Each camera path keeps three copies of its radiance per wavelength, its marks, taken as it goes (`MARKS`): when it
reaches its first vertex (a real collision in a medium or a surface; or, for a camera ray that escapes before
any, just before it meets the background), after next-event estimation there, and when it reaches its second
vertex. Marks a path never reaches are its final radiance. Cycles' light passes are then differences of marks:

- Emission: what the path gathered before its first vertex (a medium's emission along the camera ray, emissive
  surfaces and area lights the camera sees): the first mark.
- Environment: a camera ray that escapes before any vertex, what the background gave it (final − first mark).
- Direct (Volume Direct, or Diffuse Direct when the first vertex is on a surface): light arriving at the first
  vertex, by next-event estimation or by the ray leaving it hitting an emitter, a medium's emission or the
  background (third mark − first mark).
- Indirect (Volume or Diffuse Indirect): everything after the second vertex (final − third mark).

They sum to the path's radiance, so the passes sum to Combined. A fluorescent sub-path's light counts as the
emission of a medium at its collision, as Cycles counts emission: Emission when the collision is on the camera
ray (before the first vertex), Direct when it is on the ray leaving the first vertex, Indirect after.

The diffuse categories hold light × the surface's colour (Cycles divides its Diffuse Direct and Indirect passes
by a Diffuse Color pass, which the engine does not make): kept for the identity, not written as passes.

Clamping (Cycles' Light Paths ▸ Clamping, `film_clamp_light`): the direct part of a sample (Cycles' bounce 0:
everything up to the second mark, `AFTER_NEE`: emission the camera sees and next-event estimation at the first
vertex) and its indirect part (the rest, the light that the ray leaving the first vertex hits included) are each
scaled down so that the sum of their linear Rec.709 components |R| + |G| + |B| is at most 3 × the limit (Cycles
stores the limit × 3); a limit of 0 is off. Cycles clamps each contribution as it is added; here each sample's
part, per wavelength band.

Shared by both backends (`shared_math`). Part of the kernel cache's key (`numba_cache.KERNEL_SOURCES`).
"""

from ..shared_math import absolute, select, shared

# The categories a camera path's light is split into, in the order of a film's light accumulator (its slots).
EMISSION, ENVIRONMENT, VOLUME_DIRECT, VOLUME_INDIRECT, DIFFUSE_DIRECT, DIFFUSE_INDIRECT = range(6)
CATEGORIES = 6
# The marks of a path's radiance: at its first vertex, after next-event estimation there, at its second vertex.
FIRST, AFTER_NEE, SECOND, MARKS = 0, 1, 2, 3
# What a camera path met first: nothing (yet), a medium, a surface, the background.
NOTHING, MEDIUM, SURFACE, BACKGROUND = 0, 1, 2, 3


@shared
def clamp_factor(x, y, z, xyz_to_rgb, limit):
    """The factor that scales a sample's part of XYZ (x, y, z) so that its Rec.709 |R| + |G| + |B| is at most
    3 × `limit` (1 where it already is, or where `limit` is 0: no clamping)."""
    r = xyz_to_rgb[0, 0] * x + xyz_to_rgb[0, 1] * y + xyz_to_rgb[0, 2] * z
    g = xyz_to_rgb[1, 0] * x + xyz_to_rgb[1, 1] * y + xyz_to_rgb[1, 2] * z
    b = xyz_to_rgb[2, 0] * x + xyz_to_rgb[2, 1] * y + xyz_to_rgb[2, 2] * z
    total = absolute(r) + absolute(g) + absolute(b)
    return select((limit > 0.0) & (total > 3.0 * limit), 3.0 * limit / total, 1.0)


@shared
def clamped_mark(value, after_nee, direct_factor, indirect_factor):
    """A mark at or after `AFTER_NEE` (or the final radiance) once the direct part (up to the `after_nee` mark) is
    scaled by `direct_factor` and the indirect part (the rest) by `indirect_factor`."""
    return direct_factor * after_nee + indirect_factor * (value - after_nee)


@shared
def direct_slot(first):
    """The accumulator slot of the direct light of a path whose first vertex was `first` (indirect: the next)."""
    return select(first == SURFACE, DIFFUSE_DIRECT, VOLUME_DIRECT)

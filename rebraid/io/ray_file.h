#pragma once

#include <iosfwd>
#include <span>
#include <string>
#include <vector>

#include "rebraid/core/ray.h"

namespace rebraid {

/// Ray files (the project's exchange format, checked by outside tools): one ray per line,
/// `ox oy oz dx dy dz tnear tfar`, whitespace separated; `tfar` may be `inf`. Blank lines
/// and lines starting with '#' are skipped. A malformed line throws rebraid::Error naming
/// `source_name` and the line number.
///
/// What counts as malformed: not exactly 8 fields; a field that is not a whole decimal float
/// (`std::from_chars` syntax plus an optional leading '+'; `inf`/`nan` case-insensitive);
/// a value beyond float range; NaN in any field; a non-finite origin or direction component;
/// a zero direction; a non-finite or negative `tnear`; a `tfar` of `-inf` (`+inf` is the
/// usual open segment). `tnear > tfar` is accepted: such a ray has an empty segment and
/// simply misses. Values too small for a float read as the nearest float (0 or subnormal).
/// read_ray_file throws rebraid::Error naming the path when the file cannot be opened.
std::vector<Ray> read_rays(std::istream& in, const std::string& source_name);
std::vector<Ray> read_ray_file(const std::string& path);
/// Writes the same format with 9 significant digits (`%.9g`), which every float survives
/// exactly: read_rays(write_rays(r)) == r.
void write_rays(std::ostream& out, std::span<const Ray> rays);

/// Hit files: one line per ray in input order, `t instID primID` with t printed with 9
/// significant digits, or `inf -1 -1` for a miss.
void write_hits(std::ostream& out, std::span<const Hit> hits);

}  // namespace rebraid

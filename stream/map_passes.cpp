#include "stream/map_passes.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "core/system/errors.h"

namespace seamvox::map_pass {

Duplicates findDuplicateFaces(const std::string& name, const ReadPass& read, ExternalSorter<DuplicateKey>& keys,
                              ScratchFolder& scratch, const ExternalSortOptions& options) {
  Duplicates out;
  out.ranks = std::make_unique<ExternalSorter<std::uint32_t>>(scratch, options);
  keys.finish();
  DuplicateKey key, previous{kInvalidId, kInvalidId, kInvalidId, kInvalidId};
  while (keys.next(key)) {
    if (key.a == previous.a && key.b == previous.b && key.c == previous.c) {
      out.ranks->add(key.face);
      ++out.count;
    }
    previous = key;
  }
  out.ranks->finish();
  if (read.kept == out.count) {
    throw InputError(name + ": the mesh has no valid faces (" + std::to_string(read.inputFaces) +
                     " faces in the input, all degenerate or duplicates)");
  }
  return out;
}

// The geometry of the cleaned faces, read back for the few corners that need it (seam edges,

ReadPass readStream(MeshStream& stream, ScratchFolder& scratch, ExternalSorter<DuplicateKey>& duplicates,
                    CornerPositions& positions, ExternalSorter<WeldKey>* weld) {
  const std::string& name = stream.name();
  ReadPass out;
  ScratchWriter faces(scratch, "read");
  MeshChunk chunk;
  StreamChecker checker(name);  // chunks in step, 32-bit ids, (u, v) on all faces or none
  std::uint64_t nonFinite = kInvalidId;
  while (stream.next(chunk)) {
    checker.check(chunk);
    for (const Vec3f& p : chunk.positions) {
      if (!p.allFinite() && nonFinite == kInvalidId) nonFinite = out.vertices;
      positions.addVertex(p);
      if (weld) weld->add({{p.x(), p.y(), p.z()}, static_cast<std::uint32_t>(out.vertices)});
      ++out.vertices;
    }
    const bool withUV = !chunk.cornerUV.empty();
    for (std::size_t f = 0; f < chunk.triangles.size(); ++f, ++out.inputFaces) {
      const Triangle& t = chunk.triangles[f];
      if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) continue;  // degenerate: dropped
      FaceRecord record{{t[0], t[1], t[2]}, static_cast<std::uint32_t>(out.inputFaces), {}};
      for (int j = 0; j < 3; ++j) {
        if (withUV) record.uv[j][0] = chunk.cornerUV[3 * f + j].x(), record.uv[j][1] = chunk.cornerUV[3 * f + j].y();
      }
      positions.addFace(static_cast<std::uint32_t>(out.kept), t, static_cast<std::uint32_t>(out.inputFaces));
      faces.write(&record, sizeof record);
      Triangle s = t;
      std::sort(s.begin(), s.end());
      duplicates.add({s[0], s[1], s[2], static_cast<std::uint32_t>(out.kept)});
      ++out.kept;
    }
  }
  if (out.inputFaces == 0) throw InputError(name + ": the mesh has no faces");
  if (!checker.hasUV()) throw InputError(name + ": the mesh has no per-corner texture coordinates");
  if (nonFinite != kInvalidId) {
    throw InputError(name + ": vertex " + std::to_string(nonFinite) + " has a non-finite coordinate (NaN or inf)");
  }
  positions.finish();
  out.faces = faces.finish();
  return out;
}

bool WeldKey::operator<(const WeldKey& o) const {
  for (int k = 0; k < 3; ++k) {
    if (p[k] != o.p[k]) return p[k] < o.p[k];
  }
  return vertex < o.vertex;
}

std::vector<std::uint32_t> weldMap(ExternalSorter<WeldKey>& keys, std::uint64_t vertices) {
  std::vector<std::uint32_t> canonical(vertices);
  keys.finish();
  WeldKey key, first{};
  bool any = false;
  while (keys.next(key)) {
    if (!any || key.p[0] != first.p[0] || key.p[1] != first.p[1] || key.p[2] != first.p[2]) first = key, any = true;
    canonical[key.vertex] = first.vertex;
  }
  return canonical;
}

std::vector<std::pair<std::size_t, std::size_t>> glueSides(const std::vector<EdgeRecord>& sides,
                                                           const std::function<Vec3d(std::size_t)>& normalOf,
                                                           bool& clash) {
  clash = false;
  std::vector<std::pair<std::size_t, std::size_t>> glued;
  if (sides.size() < 2) return glued;  // boundary
  const bool firstForward = sides[0].forward();
  if (sides.size() == 2) {
    if (sides[1].forward() == firstForward) {
      clash = true;
    } else {
      glued.push_back({0, 1});
    }
    return glued;
  }
  struct Pair {
    double alignment;
    std::size_t x, y;  // same direction as the first side, reverse
  };
  std::vector<Vec3d> normals;
  for (std::size_t i = 0; i < sides.size(); ++i) normals.push_back(normalOf(i));
  std::vector<Pair> pairs;
  for (std::size_t x = 0; x < sides.size(); ++x) {
    if (sides[x].forward() != firstForward) continue;
    for (std::size_t y = 0; y < sides.size(); ++y) {
      if (sides[y].forward() == firstForward) continue;
      pairs.push_back({gluingAlignment(normals[x], normals[y]), x, y});  // as cleanMesh computes it
    }
  }
  std::sort(pairs.begin(), pairs.end(), [](const Pair& p, const Pair& q) {
    return p.alignment != q.alignment ? p.alignment > q.alignment : p.x != q.x ? p.x < q.x : p.y < q.y;
  });
  std::vector<std::uint8_t> used(sides.size(), 0);
  for (const Pair& pair : pairs) {
    if (used[pair.x] || used[pair.y]) continue;
    used[pair.x] = used[pair.y] = 1;
    const bool xFirst = sides[pair.x].corner() < sides[pair.y].corner();
    glued.push_back(xFirst ? std::make_pair(pair.x, pair.y) : std::make_pair(pair.y, pair.x));
  }
  return glued;
}

template <class Angle>
void addSidesToFans(FanAngleSums<Angle>& fans, const std::vector<EdgeRecord>& sides,
                    const std::vector<std::pair<std::size_t, std::size_t>>& glued, std::vector<std::uint8_t>& used) {
  const std::uint32_t low = static_cast<std::uint32_t>(sides[0].edge >> 32);
  const std::uint32_t high = static_cast<std::uint32_t>(sides[0].edge & 0xffffffffu);
  const auto start = [&](const EdgeRecord& side) { return side.forward() ? low : high; };
  used.assign(sides.size(), 0);
  for (const auto& [x, y] : glued) {
    fans.addGluedSides(start(sides[x]), start(sides[y]), sides[x].corner(), sides[y].corner(),
                       static_cast<Angle>(sides[x].startAngle), static_cast<Angle>(sides[y].startAngle));
    used[x] = used[y] = 1;
  }
  for (std::size_t i = 0; i < sides.size(); ++i) {
    if (!used[i]) fans.addSide(start(sides[i]), sides[i].corner(), static_cast<Angle>(sides[i].startAngle));
  }
}

template void addSidesToFans(FanAngleSums<float>&, const std::vector<EdgeRecord>&,
                             const std::vector<std::pair<std::size_t, std::size_t>>&, std::vector<std::uint8_t>&);
template void addSidesToFans(FanAngleSums<double>&, const std::vector<EdgeRecord>&,
                             const std::vector<std::pair<std::size_t, std::size_t>>&, std::vector<std::uint8_t>&);

}  // namespace seamvox::map_pass

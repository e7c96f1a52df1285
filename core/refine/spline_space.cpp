#include "core/refine/spline_space.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <string>

#include "core/basis/gaussian_int.h"
#include "core/system/errors.h"

namespace seamvox::detail {

namespace {

using Complex = std::complex<double>;
using Cell = std::array<std::int32_t, 3>;

enum VertexKind : std::uint8_t { kFree = 0, kLocked = 1, kAtCone = 2 };

/// A unit of Z[i] as its power of i (0..3), or -1 when the value is not a unit.
int powerOfUnit(const Complex& a) {
  constexpr double kTolerance = 1e-9;
  const Complex units[4] = {{1, 0}, {0, 1}, {-1, 0}, {0, -1}};
  for (int k = 0; k < 4; ++k) {
    if (std::abs(a - units[k]) < kTolerance) return k;
  }
  return -1;
}

/// The grid corners of the cell holding p with the trilinear weight of each (zero weights
/// included: a vertex on a grid plane).
struct Stencil {
  std::array<Cell, 8> corner;
  std::array<double, 8> weight;
};

Stencil stencilOf(const Vec3d& p, double spacing) {
  Stencil s;
  Cell base;
  Vec3d t;
  for (int a = 0; a < 3; ++a) {
    const double g = p[a] / spacing;
    const double f = std::floor(g);
    if (!(std::abs(f) < 1e9)) throw InputError("refine: a region vertex lies off the spline grid (" + std::to_string(g) + ")");
    base[a] = static_cast<std::int32_t>(f);
    t[a] = g - f;
  }
  for (int k = 0; k < 8; ++k) {
    double w = 1.0;
    for (int a = 0; a < 3; ++a) {
      const int bit = (k >> a) & 1;
      s.corner[k][a] = base[a] + bit;
      w *= bit ? t[a] : 1.0 - t[a];
    }
    s.weight[k] = w;
  }
  return s;
}

struct Entry {
  Cell g;
  VertexId v;
  double w;
};


/// Union-find whose links carry a rotation (power of i, mod 4) from a node to its parent.
struct RotationSets {
  std::vector<std::uint32_t> parent;
  std::vector<std::uint8_t> up;  // power(rho_x) = power(rho_parent) + up[x]
  void reset(std::size_t n) {
    parent.resize(n);
    up.assign(n, 0);
    for (std::size_t i = 0; i < n; ++i) parent[i] = static_cast<std::uint32_t>(i);
  }
  /// Root of x and power(rho_x) - power(rho_root), with path compression.
  std::pair<std::uint32_t, int> find(std::uint32_t x) {
    int offset = 0;
    std::uint32_t r = x;
    while (parent[r] != r) offset += up[r], r = parent[r];
    // Compress: every node on the path points at the root with its own offset.
    int remaining = offset;
    while (parent[x] != x) {
      const std::uint32_t next = parent[x];
      const int step = up[x];
      parent[x] = r;
      up[x] = static_cast<std::uint8_t>(((remaining % 4) + 4) % 4);
      remaining -= step;
      x = next;
    }
    return {r, ((offset % 4) + 4) % 4};
  }
  /// Records power(rho_b) = power(rho_a) + rel; false when it contradicts what is known.
  bool unite(std::uint32_t a, std::uint32_t b, int rel) {
    const auto [ra, oa] = find(a);
    const auto [rb, ob] = find(b);
    if (ra == rb) return ((oa + rel - ob) % 4 + 4) % 4 == 0;
    // power(rb) = power(b) - ob = power(a) + rel - ob = power(ra) + oa + rel - ob.
    const int link = ((oa + rel - ob) % 4 + 4) % 4;
    if (ra < rb) {
      parent[rb] = ra, up[rb] = static_cast<std::uint8_t>(link);
    } else {
      parent[ra] = rb, up[ra] = static_cast<std::uint8_t>((4 - link) % 4);
    }
    return true;
  }
};

}  // namespace

SplineSpace buildSplineSpace(const TriangleMesh& mesh, const std::vector<std::uint32_t>& cornerDomain,
                             const Reduction& system, const std::vector<std::uint8_t>& vertexLocked, double spacing) {
  const std::uint32_t nv = mesh.numVertices(), nf = mesh.numFaces();
  const ReducedMap& Q = system.map;
  const std::uint32_t np = system.numPositional;
  if (!(spacing > 0.0) || cornerDomain.size() != 3u * static_cast<std::size_t>(nf) || vertexLocked.size() != nv) {
    throw InputError("refine: bad spline space input (spacing " + std::to_string(spacing) + ", " +
                     std::to_string(cornerDomain.size()) + " corner domains for " + std::to_string(nf) + " faces)");
  }
  // Per vertex its positional unknown and kind; per corner the power of its domain's unit on that
  // unknown (-1: none).
  std::vector<std::uint32_t> vertexColumn(nv, kInvalidId);
  std::vector<std::uint8_t> kind(nv, kFree);
  std::vector<std::int8_t> cornerUnit(3u * static_cast<std::size_t>(nf), -1);
  for (std::uint32_t v = 0; v < nv; ++v) kind[v] = vertexLocked[v] ? kLocked : kFree;
  for (CornerId c = 0; c < 3u * nf; ++c) {
    const VertexId v = mesh.triangles[c / 3][c % 3];
    if (kind[v] == kLocked) continue;
    const std::uint32_t d = cornerDomain[c];
    std::uint32_t column = kInvalidId;
    int unit = -1;
    for (std::uint64_t k = Q.rowStart[d]; k < Q.rowStart[d + 1]; ++k) {
      if (Q.column[k] < np) column = Q.column[k], unit = powerOfUnit(Q.value[k]);
    }
    if (column == kInvalidId || unit < 0 || (vertexColumn[v] != kInvalidId && vertexColumn[v] != column)) {
      kind[v] = kAtCone;  // no positional unknown (a cone, a pin): the B-splines must vanish here
      continue;
    }
    vertexColumn[v] = column;
    cornerUnit[c] = static_cast<std::int8_t>(unit);
  }
  for (std::uint32_t v = 0; v < nv; ++v) {
    if (kind[v] == kAtCone) vertexColumn[v] = kInvalidId;
  }

  // Every vertex's B-splines with a positive value there.
  std::vector<Entry> entries;
  entries.reserve(8u * static_cast<std::size_t>(nv));
  for (VertexId v = 0; v < nv; ++v) {
    const Stencil stencil = stencilOf(mesh.position(v), spacing);
    for (int k = 0; k < 8; ++k) {
      if (stencil.weight[k] > 0.0) entries.push_back({stencil.corner[k], v, stencil.weight[k]});
    }
  }
  // The chart links along the edges between free vertices, per vertex (both directions; an edge
  // of two faces twice): power(rho_w) = power(rho_v) + rel.
  struct Link {
    VertexId w;
    std::int8_t rel;
  };
  std::vector<std::uint32_t> linkStart(nv + 1, 0);
  const auto forEachEdge = [&](auto&& visit) {
    for (FaceId f = 0; f < nf; ++f) {
      const Triangle& t = mesh.triangles[f];
      for (int k = 0; k < 3; ++k) {
        const int l = (k + 1) % 3;
        if (t[k] == t[l] || kind[t[k]] != kFree || kind[t[l]] != kFree) continue;
        visit(t[k], t[l], ((cornerUnit[3 * f + k] - cornerUnit[3 * f + l]) % 4 + 4) % 4);
      }
    }
  };
  forEachEdge([&](VertexId a, VertexId b, int) { ++linkStart[a + 1], ++linkStart[b + 1]; });
  for (VertexId v = 0; v < nv; ++v) linkStart[v + 1] += linkStart[v];
  std::vector<Link> links(linkStart[nv]);
  {
    std::vector<std::uint32_t> fill(linkStart.begin(), linkStart.end() - 1);
    forEachEdge([&](VertexId a, VertexId b, int rel) {
      links[fill[a]++] = {b, static_cast<std::int8_t>(rel)};
      links[fill[b]++] = {a, static_cast<std::int8_t>((4 - rel) % 4)};
    });
  }
  const auto entryLess = [](const Entry& x, const Entry& y) { return x.g != y.g ? x.g < y.g : x.v < y.v; };
  std::sort(entries.begin(), entries.end(), entryLess);

  // Pass 1: per B-spline, dropped (at a cone, at the border) or split into pieces with the
  // unit rho of each entry's vertex relative to its piece.
  SplineSpace space;
  std::vector<std::uint8_t> droppedAtCone(nv, 0);
  std::vector<std::uint32_t> entryPiece(entries.size(), kInvalidId);
  std::vector<std::uint8_t> entryPower(entries.size(), 0);
  std::uint32_t numPieces = 0;
  RotationSets sets;
  std::vector<std::uint32_t> rootPiece;
  // Per vertex, the B-spline (run of entries) it was last seen in and its place there.
  std::vector<std::uint32_t> seenIn(nv, kInvalidId), seenAt(nv, 0);
  std::uint32_t run = 0;
  for (std::size_t first = 0; first < entries.size(); ++run) {
    std::size_t last = first;
    while (last < entries.size() && entries[last].g == entries[first].g) ++last;
    bool atCone = false, atBorder = false;
    for (std::size_t e = first; e < last; ++e) {
      const VertexId v = entries[e].v;
      atCone = atCone || kind[v] == kAtCone;
      atBorder = atBorder || kind[v] == kLocked;
      seenIn[v] = run, seenAt[v] = static_cast<std::uint32_t>(e - first);
    }
    space.truncatedAtBorder += atBorder;
    const std::size_t n = last - first;
    if (!atCone) {
      sets.reset(n);
      for (std::size_t e = first; e < last && !atCone; ++e) {
        const VertexId v = entries[e].v;
        if (kind[v] != kFree) continue;
        for (std::uint32_t k = linkStart[v]; k < linkStart[v + 1] && !atCone; ++k) {
          const VertexId w = links[k].w;
          if (seenIn[w] == run && w > v) {
            atCone = !sets.unite(static_cast<std::uint32_t>(e - first), seenAt[w], links[k].rel);
          }
        }
      }
    }
    if (atCone) {
      ++space.droppedAtCones;
      for (std::size_t e = first; e < last; ++e) droppedAtCone[entries[e].v] = 1;
    } else {
      rootPiece.assign(n, kInvalidId);
      for (std::size_t e = first; e < last; ++e) {
        const auto [r, power] = sets.find(static_cast<std::uint32_t>(e - first));
        if (rootPiece[r] == kInvalidId) rootPiece[r] = numPieces++;
        entryPiece[e] = rootPiece[r];
        entryPower[e] = static_cast<std::uint8_t>(power);
      }
    }
    first = last;
  }
  std::vector<Link>().swap(links);

  // The free vertices of the B-splines dropped at cones keep an unknown of their own, and the
  // B-splines leave them out: near a cone the map is solved vertex by vertex, together with the
  // B-splines around it (one system, no seam between the two).
  space.ownUnknown.assign(nv, 0);
  for (VertexId v = 0; v < nv; ++v) space.ownUnknown[v] = kind[v] == kFree && droppedAtCone[v];
  // A piece this small barely moves its vertices (they sit at the far edge of its support): its
  // column would be nearly zero and the system nearly singular.
  constexpr double kMinPieceWeight = 1e-3;
  std::vector<double> pieceWeight(numPieces, 0.0);
  for (std::size_t e = 0; e < entries.size(); ++e) {
    if (entryPiece[e] != kInvalidId && kind[entries[e].v] == kFree && !space.ownUnknown[entries[e].v]) {
      pieceWeight[entryPiece[e]] = std::max(pieceWeight[entryPiece[e]], entries[e].w);
    }
  }
  std::vector<std::uint32_t> pieceColumn(numPieces, kInvalidId);
  for (std::uint32_t k = 0; k < numPieces; ++k) {
    if (pieceWeight[k] >= kMinPieceWeight) pieceColumn[k] = space.numSplines++;
  }
  struct Out {
    std::uint32_t row, column;
    Complex value;
  };
  std::vector<Out> out;
  for (std::size_t e = 0; e < entries.size(); ++e) {
    const VertexId v = entries[e].v;
    if (entryPiece[e] == kInvalidId || kind[v] != kFree || space.ownUnknown[v] ||
        pieceColumn[entryPiece[e]] == kInvalidId) {
      continue;
    }
    out.push_back({vertexColumn[v], pieceColumn[entryPiece[e]], unitPower(entryPower[e]).toComplex() * entries[e].w});
  }
  space.numColumns = space.numSplines;
  for (VertexId v = 0; v < nv; ++v) {
    if (space.ownUnknown[v]) out.push_back({vertexColumn[v], space.numColumns++, Complex(1.0, 0.0)});
  }
  std::sort(out.begin(), out.end(), [](const Out& x, const Out& y) {
    return x.row != y.row ? x.row < y.row : x.column < y.column;
  });
  space.rowStart.assign(np + 1, 0);
  for (const Out& o : out) ++space.rowStart[o.row + 1];
  for (std::uint32_t j = 0; j < np; ++j) space.rowStart[j + 1] += space.rowStart[j];
  space.column.reserve(out.size());
  space.value.reserve(out.size());
  for (const Out& o : out) space.column.push_back(o.column), space.value.push_back(o.value);
  return space;
}

}  // namespace seamvox::detail

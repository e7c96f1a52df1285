#include "stream/clean_front.h"

#include <algorithm>
#include <stdexcept>
#include <utility>

#include "core/mesh/topology.h"
#include "core/system/errors.h"
#include "stream/clean_stream.h"

namespace seamvox::detail {

namespace {

/// Vertices of more corners than this (rare) go to findFans' union-find at once.
constexpr std::size_t kOneFanCorners = 32;

/// The usual vertex, one fan: walked clockwise from its last corner round to it (closed), or from
/// the one corner no other turns to, to the corner before the boundary (open), over all corners.
/// False when that is not so (several fans, or a walk that does not cover the group).
bool findOneFan(const std::vector<CornerAround>& group, std::vector<std::uint32_t>& fanOf,
                std::vector<FanStart>& starts) {
  const std::size_t n = group.size();
  if (n > kOneFanCorners) return false;  // its searches are quadratic: findFans' own below
  const auto indexOf = [&](CornerId c) {
    for (std::size_t i = 0; i < n; ++i) {
      if (group[i].corner == c) return i;
    }
    return n;
  };
  std::size_t open = n, opens = 0;
  for (std::size_t i = 0; i < n; ++i) {
    if (group[i].clockwise == kInvalidId) open = i, ++opens;
  }
  if (opens > 1) return false;
  // The walk's first corner: the last (closed), else the one that is no corner's clockwise.
  std::size_t at = n - 1;
  if (opens == 1) {
    std::size_t first = n;
    for (std::size_t i = 0; i < n; ++i) {
      bool target = false;
      for (std::size_t j = 0; j < n && !target; ++j) target = group[j].clockwise == group[i].corner;
      if (!target) {
        if (first != n) return false;
        first = i;
      }
    }
    if (first == n) return false;
    at = first;
  }
  const std::size_t from = at;
  for (std::size_t steps = 1;; ++steps) {
    const CornerId cw = group[at].clockwise;
    if (cw == kInvalidId || cw == group[from].corner) {
      if (steps != n || (cw == kInvalidId) != (opens == 1)) return false;
      break;
    }
    at = indexOf(cw);
    if (at == n || steps == n) return false;
  }
  fanOf.assign(n, 0);
  starts.assign(1, FanStart{opens == 1 ? group[open].corner : group[n - 1].corner, opens == 1});
  return true;
}

}  // namespace

void findFans(const std::vector<CornerAround>& group, std::vector<std::uint32_t>& root,
              std::vector<std::uint32_t>& fanOf, std::vector<FanStart>& starts) {
  if (findOneFan(group, fanOf, starts)) return;
  root.resize(group.size());
  for (std::uint32_t i = 0; i < root.size(); ++i) root[i] = i;
  const auto find = [&](std::uint32_t i) {
    while (root[i] != i) i = root[i] = root[root[i]];
    return i;
  };
  const auto indexOf = [&](CornerId c) {
    const auto it = std::lower_bound(group.begin(), group.end(), c,
                                     [](const CornerAround& a, CornerId x) { return a.corner < x; });
    return it != group.end() && it->corner == c ? std::uint32_t(it - group.begin()) : kInvalidId;
  };
  for (std::uint32_t i = 0; i < group.size(); ++i) {
    if (group[i].clockwise == kInvalidId) continue;
    const std::uint32_t j = indexOf(group[i].clockwise);
    if (j == kInvalidId) continue;
    const std::uint32_t a = find(i), b = find(j);
    if (a != b) root[std::max(a, b)] = std::min(a, b);
  }
  // Roots are the smallest indices of their sets, so a fan's root comes before its other
  // corners: numbered when met, in the order of the fans' smallest corners.
  fanOf.assign(group.size(), kInvalidId);
  std::uint32_t fans = 0;
  for (std::uint32_t i = 0; i < group.size(); ++i) {
    const std::uint32_t r = find(i);
    if (fanOf[r] == kInvalidId) fanOf[r] = fans++;
    fanOf[i] = fanOf[r];
  }
  const auto clockwiseOf = [&](CornerId c) {
    const std::uint32_t i = indexOf(c);
    return i == kInvalidId ? kInvalidId : group[i].clockwise;
  };
  // From corner d clockwise to the last corner before a boundary edge, or d itself when the fan
  // closes.
  const auto mostClockwise = [&](CornerId d) {
    CornerId s = d;
    for (;;) {
      const CornerId cw = clockwiseOf(s);
      if (cw == kInvalidId) return s;
      if (cw == d) return d;
      s = cw;
    }
  };
  starts.clear();
  for (std::uint32_t k = 0; k < fans; ++k) {
    CornerId first = kInvalidId;
    for (std::size_t j = 0; j < group.size() && first == kInvalidId; ++j) {
      if (fanOf[j] == k) first = group[j].corner;
    }
    const CornerId start = mostClockwise(fans == 1 ? group.back().corner : first);
    starts.push_back({start, clockwiseOf(start) == kInvalidId});
  }
}

namespace {

constexpr CornerId kUnset = kInvalidId - 1;

/// Values for ids 0, 1, ... that enter in order and are set in any order, written to a scratch
/// file in id order: the oldest go out once set, or when the window is full (then an unset one is
/// written as kInvalidId and its value, set later, patched in place at the end).
class OrderedWindow {
 public:
  OrderedWindow(ScratchFolder& folder, std::size_t capacity, const char* stage)
      : folder_(folder), stage_(stage), writer_(folder, stage) {
    std::size_t n = 2;
    while (n < capacity) n *= 2;
    ring_.assign(n, kUnset);
    mask_ = n - 1;
  }
  /// A new id at the end, unset.
  void push() {
    if (end_ - base_ == ring_.size()) write(ring_.size() / 2);
    ring_[end_++ & mask_] = kUnset;
  }
  void set(std::uint64_t id, CornerId value) {
    if (id >= base_) {
      ring_[id & mask_] = value;
    } else if (value != kInvalidId) {
      late_.emplace_back(id, value);
    }
  }
  /// Writes the leading values that are set.
  void writeSet() {
    std::uint64_t n = 0;
    while (base_ + n < end_ && ring_[(base_ + n) & mask_] != kUnset) ++n;
    write(n);
  }
  std::size_t lateValues() const { return late_.size(); }
  /// The file written so far removed (the pass gave up).
  void discard() { folder_.remove(writer_.finish()); }
  /// Every value set: the file with tail appended, late values patched.
  ScratchFile finish(const std::vector<CornerId>& tail) {
    writeSet();
    if (base_ != end_) throw std::logic_error("glueAlongFront: a value never set");
    writer_.write(tail.data(), tail.size() * sizeof(CornerId));
    const ScratchFile file = writer_.finish();
    std::sort(late_.begin(), late_.end());
    ScratchUpdater update(folder_, file, stage_);
    std::vector<CornerId> run;
    for (std::size_t i = 0; i < late_.size();) {
      std::size_t j = i;
      run.clear();
      while (j < late_.size() && late_[j].first == late_[i].first + (j - i)) run.push_back(late_[j++].second);
      update.writeAt(late_[i].first * sizeof(CornerId), run.data(), run.size() * sizeof(CornerId));
      i = j;
    }
    return file;
  }

 private:
  /// Writes the n oldest values (unset ones as kInvalidId).
  void write(std::uint64_t n) {
    while (n > 0) {
      const std::size_t at = static_cast<std::size_t>(base_ & mask_);
      const std::size_t piece = static_cast<std::size_t>(std::min<std::uint64_t>(n, ring_.size() - at));
      for (std::size_t i = at; i < at + piece; ++i) {
        if (ring_[i] == kUnset) ring_[i] = kInvalidId;
      }
      writer_.write(ring_.data() + at, piece * sizeof(CornerId));
      base_ += piece;
      n -= piece;
    }
  }

  ScratchFolder& folder_;
  std::string stage_;
  ScratchWriter writer_;
  std::vector<CornerId> ring_;
  std::uint64_t mask_ = 0, base_ = 0, end_ = 0;  // ids [base_, end_) in the ring
  std::vector<std::pair<std::uint64_t, CornerId>> late_;
};

/// An edge held by the vertex of its two that meets its last face first (the other's id larger on a
/// tie): its other vertex and its sides (the opposite corners), the first's direction.
struct OwnedEdge {
  VertexId other, from;  ///< from: where side[0] runs from
  CornerId side[2];
  std::uint32_t sides;
};

/// A vertex between its first and last face: the edges it holds, its corners with their clockwise
/// neighbours (as the edges before them are complete) and how many corners it has met.
struct OpenVertex {
  std::vector<OwnedEdge> edges;
  std::vector<CornerAround> corners;
  std::uint32_t met = 0;
};

/// Per open vertex about this much (its vectors' usual capacity included).
constexpr std::uint64_t kOpenVertexBytes = sizeof(OpenVertex) + 8 * sizeof(OwnedEdge) + 8 * sizeof(CornerAround) + 4;

class FrontPass {
 public:
  FrontPass(ScratchFolder& folder, std::uint64_t numVertices, const std::vector<FaceId>& lastFace,
            const FrontGlueOptions& options)
      : folder_(folder),
        last_(lastFace),
        options_(options),
        slot_(static_cast<std::size_t>(numVertices), kInvalidId),
        opposite_(folder, options.windowValues, "clean: front"),
        starts_(folder, options.windowValues, "clean: front") {}

  /// Face f's corners and edges in, then its vertices that meet their last face out. False when
  /// the pass cannot go on (result_.why says why).
  bool add(FaceId f, const Triangle& t) {
    for (int k = 0; k < 3; ++k) {
      const VertexId v = t[k];
      if (slot_[v] != kInvalidId) continue;
      if (v != nextVertex_) return stop("vertices not numbered in the order the faces name them");
      if (!open(v)) return false;
    }
    for (int k = 0; k < 3; ++k) {
      opposite_.push();
      ++vertex(t[k]).met;
    }
    for (int k = 0; k < 3; ++k) {
      const VertexId from = t[(k + 1) % 3], to = t[(k + 2) % 3];
      const bool fromFirst = last_[from] != last_[to] ? last_[from] < last_[to] : from < to;
      const VertexId owner = fromFirst ? from : to, other = fromFirst ? to : from;
      // Held sorted by the other vertex: a vertex of many open edges (a fan's centre) stays cheap.
      std::vector<OwnedEdge>& edges = vertex(owner).edges;
      const auto it = std::lower_bound(edges.begin(), edges.end(), other,
                                       [](const OwnedEdge& e, VertexId v) { return e.other < v; });
      const CornerId side = 3 * f + k;
      if (it == edges.end() || it->other != other) {
        edges.insert(it, OwnedEdge{other, from, {side, kInvalidId}, 1});
      } else if (it->sides == 2) {
        return stop("an edge of more than two faces");
      } else if (it->from == from) {
        return stop("two faces along an edge in one direction");
      } else {
        it->side[1] = side;
        it->sides = 2;
      }
    }
    for (const VertexId v : t) {
      if (last_[v] == f) completeEdges(v);
    }
    for (const VertexId v : t) {
      if (last_[v] == f) close(v);
    }
    if ((f & 1023) == 0) {
      opposite_.writeSet();
      starts_.writeSet();
      if (2 * sizeof(CornerId) * options_.windowValues + states_.size() * kOpenVertexBytes +
              8 * (opposite_.lateValues() + starts_.lateValues() + copyCorners_) >
          options_.memoryBytes) {
        return stop("the open front outgrew its memory");
      }
    }
    return true;
  }

  FrontGlueResult finish(std::uint64_t numVertices) {
    if (free_.size() != states_.size() || nextVertex_ != numVertices) {
      throw std::logic_error("glueAlongFront: vertices left open after the last face");
    }
    // The copies numbered after the other vertices, by vertex then fan; their starts after the
    // others', open ones after the other boundary vertices.
    std::sort(result_.copies.begin(), result_.copies.end(),
              [](const FanCopy& a, const FanCopy& b) { return a.vertex != b.vertex ? a.vertex < b.vertex : a.fan < b.fan; });
    std::vector<CornerId> copyStarts;
    std::sort(result_.boundary.begin(), result_.boundary.end());
    for (std::size_t i = 0; i < result_.copies.size(); ++i) {
      copyStarts.push_back(result_.copies[i].start.start);
      if (result_.copies[i].start.open) result_.boundary.push_back(static_cast<VertexId>(numVertices + i));
    }
    result_.lateValues = opposite_.lateValues() + starts_.lateValues();
    result_.opposite = opposite_.finish({});
    result_.vertexCorner = starts_.finish(copyStarts);
    result_.largestFront = states_.size();
    result_.glued = true;
    return std::move(result_);
  }

  /// The files written so far removed; the result says why the pass gave up.
  FrontGlueResult discard() {
    opposite_.discard();
    starts_.discard();
    FrontGlueResult failed;
    failed.why = result_.why;
    return failed;
  }

 private:
  bool stop(const char* why) {
    result_.why = why;
    return false;
  }

  OpenVertex& vertex(VertexId v) { return states_[slot_[v]]; }

  bool open(VertexId v) {
    ++nextVertex_;
    starts_.push();
    if (free_.empty()) {
      free_.push_back(static_cast<std::uint32_t>(states_.size()));
      states_.emplace_back();
    }
    slot_[v] = free_.back();
    free_.pop_back();
    return true;
  }

  /// The edges v holds are complete: glued or boundary; each side's next corner learns its
  /// clockwise neighbour.
  void completeEdges(VertexId v) {
    std::vector<OwnedEdge>& edges = vertex(v).edges;
    for (const OwnedEdge& e : edges) {
      const VertexId to = e.from == v ? e.other : v;
      if (e.sides == 1) {
        opposite_.set(e.side[0], kInvalidId);
        around(e.from, nextCorner(e.side[0]), kInvalidId);
        continue;
      }
      opposite_.set(e.side[0], e.side[1]);
      opposite_.set(e.side[1], e.side[0]);
      around(e.from, nextCorner(e.side[0]), prevCorner(e.side[1]));
      around(to, nextCorner(e.side[1]), prevCorner(e.side[0]));
    }
    edges.clear();
  }

  void around(VertexId v, CornerId corner, CornerId clockwise) { vertex(v).corners.push_back({v, corner, clockwise}); }

  /// v's fans: the first keeps v, the others become copies.
  void close(VertexId v) {
    OpenVertex& o = vertex(v);
    if (o.corners.size() != o.met || !o.edges.empty()) throw std::logic_error("glueAlongFront: a vertex closed early");
    std::sort(o.corners.begin(), o.corners.end(), [](const CornerAround& a, const CornerAround& b) { return a.corner < b.corner; });
    findFans(o.corners, root_, fanOf_, fans_);
    starts_.set(v, fans_[0].start);
    if (fans_[0].open) result_.boundary.push_back(v);
    for (std::uint32_t k = 1; k < fans_.size(); ++k) {
      FanCopy copy{v, k, fans_[k], {}};
      for (std::size_t j = 0; j < o.corners.size(); ++j) {
        if (fanOf_[j] == k) copy.corners.push_back(o.corners[j].corner);
      }
      copyCorners_ += copy.corners.size() + 2;
      result_.copies.push_back(std::move(copy));
    }
    result_.nonManifoldVertices += fans_.size() > 1;
    o.corners.clear();
    o.met = 0;
    free_.push_back(slot_[v]);
    slot_[v] = kInvalidId;
  }

  ScratchFolder& folder_;
  const std::vector<FaceId>& last_;
  FrontGlueOptions options_;
  std::vector<std::uint32_t> slot_;  // per vertex: its OpenVertex while open
  std::vector<OpenVertex> states_;
  std::vector<std::uint32_t> free_;
  OrderedWindow opposite_, starts_;
  VertexId nextVertex_ = 0;
  std::uint64_t copyCorners_ = 0;
  std::vector<std::uint32_t> root_, fanOf_;
  std::vector<FanStart> fans_;
  FrontGlueResult result_;
};

}  // namespace

FrontGlueResult glueAlongFront(ScratchFolder& folder, const ScratchFile& faces, std::uint64_t numFaces,
                               std::uint64_t numVertices, const std::vector<FaceId>& lastFace,
                               const FrontGlueOptions& options) {
  FrontPass pass(folder, numVertices, lastFace, options);
  ScratchReader in(folder, faces, "clean: front");
  std::vector<CleanFace> block(std::size_t(1) << 14);
  for (std::uint64_t f = 0; f < numFaces;) {
    const std::size_t n = static_cast<std::size_t>(std::min<std::uint64_t>(block.size(), numFaces - f));
    if (!in.read(block.data(), n * sizeof(CleanFace))) throw IoError(faces.path + ": scratch faces end early");
    for (std::size_t i = 0; i < n; ++i, ++f) {
      if (!pass.add(static_cast<FaceId>(f), block[i].triangle)) return pass.discard();
    }
  }
  return pass.finish(numVertices);
}

}  // namespace seamvox::detail

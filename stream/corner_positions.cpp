#include "stream/corner_positions.h"

#include <tuple>

#include "core/system/errors.h"

namespace seamvox {

using corner_detail::CornerPosition;
using corner_detail::CornerRequest;

bool CornerRequest::operator<(const CornerRequest& o) const {
  return std::tie(vertex, face, j) < std::tie(o.vertex, o.face, o.j);
}

CornerPositions::CornerPositions(const std::string& name, ScratchFolder& scratch, std::uint64_t declaredVertices,
                                 std::uint64_t memoryBytes, const ExternalSortOptions& sortOptions)
    : name_(name), scratch_(scratch), sortOptions_(sortOptions) {
  if (declaredVertices > 0 && declaredVertices * sizeof(Vec3f) <= memoryBytes) {
    positions_.reserve(declaredVertices);
  } else {
    file_ = std::make_unique<ScratchWriter>(scratch, "read");
    requests_ = std::make_unique<ExternalSorter<CornerRequest>>(scratch, sortOptions);
  }
}

CornerPositions::~CornerPositions() = default;

void CornerPositions::addVertex(const Vec3f& p) {
  ++vertices_;
  if (!file_) {
    positions_.push_back(p);
    return;
  }
  const float xyz[3] = {p.x(), p.y(), p.z()};
  file_->write(xyz, sizeof xyz);
}

void CornerPositions::addFace(std::uint32_t rank, const Triangle& t, std::uint32_t inputFace) {
  if (!requests_) return;
  for (std::uint32_t j = 0; j < 3; ++j) requests_->add({t[j], rank, j, inputFace});
}

void CornerPositions::finish() {
  if (!requests_) return;
  const ScratchFile positions = file_->finish();
  file_.reset();
  corners_ = std::make_unique<ExternalSorter<CornerPosition>>(scratch_, sortOptions_);
  join(positions);
  requests_.reset();
  scratch_.remove(positions);
}

void CornerPositions::face(std::uint64_t rank, const std::uint32_t (&v)[3], std::uint32_t inputFace,
                           Vec3d (&p)[3]) {
  for (int j = 0; j < 3; ++j) {
    if (!corners_) {
      if (v[j] >= positions_.size()) {
        throw InputError(name_ + ": face " + std::to_string(inputFace) + " refers to vertex " + std::to_string(v[j]) +
                         " but there are only " + std::to_string(positions_.size()) + " vertices");
      }
      p[j] = positions_[v[j]].cast<double>();
      continue;
    }
    CornerPosition c;
    if (!corners_->next(c) || c.corner != 3 * rank + j) throw IoError(scratch_.path() + ": corner positions out of step");
    p[j] = Vec3f(c.p[0], c.p[1], c.p[2]).cast<double>();
  }
}

void CornerPositions::join(const ScratchFile& positions) {
  requests_->finish();
  ScratchReader reader(scratch_, positions, "positions");
  std::uint64_t vertex = 0;
  float p[3] = {0, 0, 0};
  bool haveVertex = false;
  CornerRequest r;
  // Out of range (the readers check first): the first face in input order that refers to one.
  CornerRequest bad{0, 0, 0, kInvalidId};
  while (requests_->next(r)) {
    if (r.vertex >= vertices_) {
      if (r.inputFace < bad.inputFace || (r.inputFace == bad.inputFace && r.j < bad.j)) bad = r;
      continue;
    }
    while (!haveVertex || vertex < r.vertex) {
      if (!reader.read(p, sizeof p)) throw IoError(positions.path + ": scratch positions end early");
      vertex += haveVertex;
      haveVertex = true;
    }
    corners_->add({3 * std::uint64_t(r.face) + r.j, {p[0], p[1], p[2]}});
  }
  if (bad.inputFace != kInvalidId) {
    throw InputError(name_ + ": face " + std::to_string(bad.inputFace) + " refers to vertex " +
                     std::to_string(bad.vertex) + " but there are only " + std::to_string(vertices_) + " vertices");
  }
  corners_->finish();
}

}  // namespace seamvox

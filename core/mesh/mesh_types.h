#pragma once
/// Id and vector types shared by the mesh and its attribute maps.
#include <Eigen/Core>
#include <array>
#include <cstdint>

namespace seamvox {

using VertexId = std::uint32_t;  ///< index into positions
using FaceId = std::uint32_t;    ///< index into triangles
using CornerId = std::uint32_t;  ///< 3 * face + k, k in {0, 1, 2}
/// Marks "no such element" (e.g. the opposite of a boundary corner).
constexpr std::uint32_t kInvalidId = 0xffffffffu;

using Triangle = std::array<VertexId, 3>;
using Vec3f = Eigen::Vector3f;
using Vec3d = Eigen::Vector3d;
using Vec2d = Eigen::Vector2d;

}  // namespace seamvox

// A triangle mesh with float vertices relative to a double origin (UTM coordinates keep their
// precision), and its topology checks and clean-up.
#pragma once

#include <cstdint>

#include <Eigen/Geometry>
#include <cstddef>
#include <vector>

#include "core/geometry/scan.h"

namespace scanreg::merge {

// What the measurements say at a merged vertex (issues 34 and 35): the colour of the scan point
// nearest it, and how far that point is — a vertex far from every measured point lies on surface
// the field interpolated (a filled hole, or the inside of a wide range-image triangle).
struct VertexInfo {
  Rgb colour{};       // the nearest coloured scan point's; black when no scan point near has colour
  // Metres to the nearest scan point, at most kMaxGapVoxels voxels; at least 2 voxels (MarkedGap)
  // where the vertex rests on filled values (Mesh::on_filled), however near a point.
  float gap_m = 0.0f;
};
constexpr double kMaxGapVoxels = 4.0;

struct Mesh {
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();  // world position of vertex (0, 0, 0)
  std::vector<Eigen::Vector3f> vertices;             // metres, world minus origin
  std::vector<Eigen::Vector3i> triangles;            // counter-clockwise seen from outside
  std::vector<VertexInfo> info;                      // one per vertex, or empty (not described)
  // One per vertex from Marching Cubes (empty otherwise): 1 where every cube around the vertex's grid
  // edge has a corner whose value was filled (MergeOptions::fill_holes: no measurement beside it),
  // so that without the filled values the vertex would not be there; DescribeVertices marks them.
  std::vector<std::uint8_t> on_filled;
  bool coloured = false;                             // info holds the scans' colour
};

struct EdgeCounts {
  std::size_t boundary = 0;     // edges of exactly one triangle
  std::size_t manifold = 0;     // edges of exactly two triangles
  std::size_t non_manifold = 0;  // edges of three or more
};
EdgeCounts CountEdges(const Mesh& mesh);
// Every edge shared by exactly two triangles (and at least one triangle).
bool IsWatertight(const Mesh& mesh);

// Triangle counts of the connected pieces (triangles sharing a vertex), largest first.
std::vector<std::size_t> PieceSizes(const Mesh& mesh);
// Removes pieces with fewer triangles than min_fraction x the largest piece's, and unused
// vertices. Returns the number of triangles removed.
std::size_t RemoveSmallPieces(Mesh& mesh, double min_fraction);

}  // namespace scanreg::merge

#include "core/simulate/scene.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

namespace scanreg {
namespace {

constexpr double kEps = 1e-9;

// Entry distance of the ray into an axis-aligned box, or +inf when it misses within t_max.
double EnterBox(const Eigen::AlignedBox3d& b, const Eigen::Vector3d& o, const Eigen::Vector3d& inv, double t_max) {
  double t0 = 0.0, t1 = t_max;
  for (int i = 0; i < 3; ++i) {
    double a = (b.min()[i] - o[i]) * inv[i], c = (b.max()[i] - o[i]) * inv[i];
    if (a > c) std::swap(a, c);
    t0 = std::max(t0, a);
    t1 = std::min(t1, c);
    if (t0 > t1) return std::numeric_limits<double>::infinity();
  }
  return t0;
}

}  // namespace

int Scene::AddTexture(const SurfaceTexture& texture) {
  textures_.push_back(texture);
  return static_cast<int>(textures_.size()) - 1;
}

int Scene::AddRectangle(const Eigen::Vector3d& center, const Eigen::Vector3d& u_axis, const Eigen::Vector3d& v_axis,
                        double half_u, double half_v, int texture) {
  Primitive p;
  p.kind = Kind::kRectangle;
  p.center = center;
  const Eigen::Vector3d u = u_axis.normalized(), v = v_axis.normalized();
  p.axes.col(0) = u;
  p.axes.col(1) = v;
  p.axes.col(2) = u.cross(v).normalized();
  p.half = Eigen::Vector3d(half_u, half_v, 0.0);
  p.texture.fill(texture);
  const Eigen::Vector3d ext = half_u * u.cwiseAbs() + half_v * v.cwiseAbs() + Eigen::Vector3d::Constant(1e-6);
  p.bounds = Eigen::AlignedBox3d(center - ext, center + ext);
  prims_.push_back(p);
  return static_cast<int>(prims_.size()) - 1;
}

int Scene::AddBox(const Eigen::Vector3d& center, const Eigen::Vector3d& half_extents, double yaw_rad,
                  const std::array<int, 6>& face_textures) {
  Primitive p;
  p.kind = Kind::kBox;
  p.center = center;
  p.axes = Eigen::AngleAxisd(yaw_rad, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  p.half = half_extents;
  p.texture = face_textures;
  const Eigen::Vector3d ext = p.axes.cwiseAbs() * half_extents;
  p.bounds = Eigen::AlignedBox3d(center - ext, center + ext);
  prims_.push_back(p);
  return static_cast<int>(prims_.size()) - 1;
}

int Scene::AddBox(const Eigen::Vector3d& center, const Eigen::Vector3d& half_extents, double yaw_rad, int texture) {
  return AddBox(center, half_extents, yaw_rad, {texture, texture, texture, texture, texture, texture});
}

int Scene::AddCylinder(const Eigen::Vector2d& center_xy, double radius, double z_min, double z_max, int texture) {
  Primitive p;
  p.kind = Kind::kCylinder;
  p.center = Eigen::Vector3d(center_xy.x(), center_xy.y(), 0.0);
  p.axes.setIdentity();
  p.half = Eigen::Vector3d(radius, z_min, z_max);
  p.texture.fill(texture);
  p.bounds = Eigen::AlignedBox3d(Eigen::Vector3d(center_xy.x() - radius, center_xy.y() - radius, z_min),
                                 Eigen::Vector3d(center_xy.x() + radius, center_xy.y() + radius, z_max));
  prims_.push_back(p);
  return static_cast<int>(prims_.size()) - 1;
}

int Scene::AddSphere(const Eigen::Vector3d& center, double radius, int texture) {
  Primitive p;
  p.kind = Kind::kSphere;
  p.center = center;
  p.axes.setIdentity();
  p.half = Eigen::Vector3d(radius, 0.0, 0.0);
  p.texture.fill(texture);
  p.bounds = Eigen::AlignedBox3d(center.array() - radius, center.array() + radius);
  prims_.push_back(p);
  return static_cast<int>(prims_.size()) - 1;
}

bool Scene::HitPrimitive(int index, const Eigen::Vector3d& o, const Eigen::Vector3d& d, double* t_best, int* face,
                         Eigen::Vector2d* uv, Eigen::Vector3d* normal) const {
  const Primitive& p = prims_[index];
  switch (p.kind) {
    case Kind::kRectangle: {
      const Eigen::Vector3d n = p.axes.col(2);
      const double denom = d.dot(n);
      if (std::abs(denom) < 1e-12) return false;
      const double t = (p.center - o).dot(n) / denom;
      if (t <= kEps || t >= *t_best) return false;
      const Eigen::Vector3d q = o + t * d - p.center;
      const double s = q.dot(p.axes.col(0)), w = q.dot(p.axes.col(1));
      if (std::abs(s) > p.half.x() || std::abs(w) > p.half.y()) return false;
      *t_best = t;
      *face = 0;
      *uv = Eigen::Vector2d(s, w);
      *normal = n;
      return true;
    }
    case Kind::kBox: {
      const Eigen::Vector3d lo = p.axes.transpose() * (o - p.center);
      const Eigen::Vector3d ld = p.axes.transpose() * d;
      double t0 = -std::numeric_limits<double>::infinity(), t1 = std::numeric_limits<double>::infinity();
      int axis = -1;
      for (int i = 0; i < 3; ++i) {
        if (std::abs(ld[i]) < 1e-15) {
          if (std::abs(lo[i]) > p.half[i]) return false;
          continue;
        }
        double a = (-p.half[i] - lo[i]) / ld[i], b = (p.half[i] - lo[i]) / ld[i];
        if (a > b) std::swap(a, b);
        if (a > t0) {
          t0 = a;
          axis = i;
        }
        t1 = std::min(t1, b);
      }
      if (axis < 0 || t0 > t1 || t0 <= kEps || t0 >= *t_best) return false;  // miss, or origin inside
      const Eigen::Vector3d q = lo + t0 * ld;
      const bool positive = ld[axis] < 0.0;  // entering through the +axis face
      const Eigen::Vector3d& h = p.half;
      Eigen::Vector3d n_local = Eigen::Vector3d::Zero();
      n_local[axis] = positive ? 1.0 : -1.0;
      *face = 2 * axis + (positive ? 0 : 1);
      switch (*face) {
        case 0: *uv = Eigen::Vector2d(q.y() + h.y(), q.z() + h.z()); break;
        case 1: *uv = Eigen::Vector2d(h.y() - q.y(), q.z() + h.z()); break;
        case 2: *uv = Eigen::Vector2d(h.x() - q.x(), q.z() + h.z()); break;
        case 3: *uv = Eigen::Vector2d(q.x() + h.x(), q.z() + h.z()); break;
        default: *uv = Eigen::Vector2d(q.x(), q.y()); break;
      }
      *t_best = t0;
      *normal = p.axes * n_local;
      return true;
    }
    case Kind::kCylinder: {
      const double r = p.half.x(), z0 = p.half.y(), z1 = p.half.z();
      const double dx = o.x() - p.center.x(), dy = o.y() - p.center.y();
      bool hit = false;
      const double a = d.x() * d.x() + d.y() * d.y();
      const double b = 2.0 * (dx * d.x() + dy * d.y());
      const double c = dx * dx + dy * dy - r * r;
      if (c > 0.0 && a > 1e-15) {
        const double disc = b * b - 4.0 * a * c;
        if (disc >= 0.0) {
          const double t = (-b - std::sqrt(disc)) / (2.0 * a);
          const double z = o.z() + t * d.z();
          if (t > kEps && t < *t_best && z >= z0 && z <= z1) {
            const double px = dx + t * d.x(), py = dy + t * d.y();
            *t_best = t;
            *face = 0;
            *uv = Eigen::Vector2d(std::atan2(py, px) * r, z - z0);
            *normal = Eigen::Vector3d(px / r, py / r, 0.0);
            hit = true;
          }
        }
      }
      if (d.z() < 0.0 && o.z() > z1) {  // top cap, seen from above
        const double t = (z1 - o.z()) / d.z();
        const double px = dx + t * d.x(), py = dy + t * d.y();
        if (t > kEps && t < *t_best && px * px + py * py <= r * r) {
          *t_best = t;
          *face = 4;
          *uv = Eigen::Vector2d(px, py);
          *normal = Eigen::Vector3d::UnitZ();
          hit = true;
        }
      }
      return hit;
    }
    case Kind::kSphere: {
      const double r = p.half.x();
      const Eigen::Vector3d oc = o - p.center;
      const double b = oc.dot(d), c = oc.squaredNorm() - r * r;
      if (c <= 0.0) return false;  // origin inside
      const double disc = b * b - c;
      if (disc < 0.0) return false;
      const double t = -b - std::sqrt(disc);
      if (t <= kEps || t >= *t_best) return false;
      const Eigen::Vector3d n = (oc + t * d) / r;
      *t_best = t;
      *face = 0;
      *uv = Eigen::Vector2d(std::atan2(n.y(), n.x()) * r, n.z() * r);
      *normal = n;
      return true;
    }
  }
  return false;
}

std::optional<Scene::Hit> Scene::MakeHit(int index, double t, int face, const Eigen::Vector2d& uv,
                                         const Eigen::Vector3d& normal, const Eigen::Vector3d& dir,
                                         double footprint_half_m) const {
  const int tex = prims_[index].texture[face];
  Hit hit;
  hit.range = t;
  hit.normal = normal.dot(dir) > 0.0 ? Eigen::Vector3d(-normal) : normal;
  hit.albedo = (tex >= 0 && tex < static_cast<int>(textures_.size())) ? textures_[tex].Albedo(uv.x(), uv.y(), footprint_half_m) : 0.5;
  hit.primitive = index;
  return hit;
}

std::optional<Scene::Hit> Scene::IntersectBruteForce(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir,
                                                     double max_range) const {
  double t = max_range;
  int best = -1, face = 0;
  Eigen::Vector2d uv;
  Eigen::Vector3d n;
  for (int i = 0; i < num_primitives(); ++i)
    if (HitPrimitive(i, origin, dir, &t, &face, &uv, &n)) best = i;
  if (best < 0) return std::nullopt;
  return MakeHit(best, t, face, uv, n, dir);
}

int Scene::BuildNode(int first, int count) {
  Node node;
  node.bounds.setEmpty();
  Eigen::AlignedBox3d centroids;
  centroids.setEmpty();
  for (int i = first; i < first + count; ++i) {
    node.bounds.extend(prims_[order_[i]].bounds);
    centroids.extend(prims_[order_[i]].bounds.center());
  }
  const int index = static_cast<int>(nodes_.size());
  nodes_.push_back(node);
  if (count <= 2) {
    nodes_[index].first = first;
    nodes_[index].count = count;
    return index;
  }
  int axis = 0;
  centroids.sizes().maxCoeff(&axis);
  const int mid = first + count / 2;
  std::nth_element(order_.begin() + first, order_.begin() + mid, order_.begin() + first + count, [&](int a, int b) {
    return prims_[a].bounds.center()[axis] < prims_[b].bounds.center()[axis];
  });
  const int left = BuildNode(first, mid - first);
  const int right = BuildNode(mid, first + count - mid);
  nodes_[index].left = left;
  nodes_[index].right = right;
  return index;
}

void Scene::Build() {
  nodes_.clear();
  order_.resize(prims_.size());
  std::iota(order_.begin(), order_.end(), 0);
  if (!prims_.empty()) BuildNode(0, num_primitives());
}

std::optional<Scene::Hit> Scene::Intersect(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir,
                                           double max_range, double footprint_per_m) const {
  if (nodes_.empty()) return IntersectBruteForce(origin, dir, max_range);
  Eigen::Vector3d inv;
  for (int i = 0; i < 3; ++i) inv[i] = 1.0 / (dir[i] != 0.0 ? dir[i] : 1e-300);
  double t = max_range;
  int best = -1, face = 0;
  Eigen::Vector2d uv;
  Eigen::Vector3d n;
  int stack[64];
  int top = 0;
  stack[top++] = 0;
  while (top > 0) {
    const Node& node = nodes_[stack[--top]];
    if (EnterBox(node.bounds, origin, inv, t) > t) continue;
    if (node.count > 0) {
      for (int i = node.first; i < node.first + node.count; ++i)
        if (HitPrimitive(order_[i], origin, dir, &t, &face, &uv, &n)) best = order_[i];
      continue;
    }
    const double tl = EnterBox(nodes_[node.left].bounds, origin, inv, t);
    const double tr = EnterBox(nodes_[node.right].bounds, origin, inv, t);
    // Push the farther child first so the nearer one is visited first.
    if (tl <= tr) {
      if (tr <= t) stack[top++] = node.right;
      if (tl <= t) stack[top++] = node.left;
    } else {
      if (tl <= t) stack[top++] = node.left;
      if (tr <= t) stack[top++] = node.right;
    }
  }
  if (best < 0) return std::nullopt;
  return MakeHit(best, t, face, uv, n, dir, t * footprint_per_m);
}

}  // namespace scanreg

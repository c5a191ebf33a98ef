#include "core/report/network_image.h"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "core/report/canvas.h"
#include "core/io/project_tree.h"

namespace scanreg::report {
namespace {

constexpr int kWidth = 1000;
constexpr int kMapHeight = 620;
constexpr int kStripHeight = 90;
constexpr int kLegendHeight = 70;
constexpr int kMargin = 60;
const cv::Scalar kUnregistered(150, 150, 150);

// A round length (1, 2 or 5 x 10^k) close to `about`.
double NiceLength(double about) {
  const double p = std::pow(10.0, std::floor(std::log10(about)));
  for (double m : {1.0, 2.0, 5.0})
    if (m * p >= about * 0.7) return m * p;
  return 10 * p;
}

std::string LengthLabel(double metres) {
  char buf[32];
  if (metres >= 1) {
    std::snprintf(buf, sizeof buf, "%g m", metres);
  } else {
    std::snprintf(buf, sizeof buf, "%g cm", metres * 100);
  }
  return buf;
}

void DrawLink(cv::Mat& image, cv::Point2d a, cv::Point2d b, const io::LinkRecord& l) {
  const cv::Scalar color = StatusColor(l.status);
  if (l.loop_check) {
    DrawDashedLine(image, a, b, color, 2, 2, 6);
  } else if (!io::IsTreeLink(l)) {
    DrawDashedLine(image, a, b, color, 1, 9, 6);
  } else {
    cv::line(image, a, b, cv::Scalar(235, 235, 235), 11, cv::LINE_AA);
    cv::line(image, a, b, color, 5, cv::LINE_AA);
  }
}

void DrawLegend(cv::Mat& image, int top) {
  struct Entry {
    const char* label;
    io::LinkStatus status;
    int style;  // 0 tree, 1 failed, 2 loop check
  };
  const Entry entries[] = {{"tree link ok", io::LinkStatus::kOk, 0},
                           {"tree link weak", io::LinkStatus::kWeak, 0},
                           {"failed attempt", io::LinkStatus::kFailed, 1},
                           {"loop check (status colour)", io::LinkStatus::kOk, 2}};
  int x = 20;
  const int y = top + 25;
  for (const Entry& e : entries) {
    io::LinkRecord l;
    l.status = e.status;
    l.loop_check = e.style == 2;
    DrawLink(image, {double(x), double(y)}, {double(x + 40), double(y)}, l);
    DrawText(image, e.label, {x + 48, y + 5}, 0.45, kInk);
    x += 60 + TextSize(e.label, 0.45).width;
  }
  const int y2 = top + 55;
  cv::circle(image, {30, y2}, 7, kInk, cv::FILLED, cv::LINE_AA);
  cv::circle(image, {30, y2}, 11, kInk, 2, cv::LINE_AA);
  DrawText(image, "root", {48, y2 + 5}, 0.45, kInk);
  cv::circle(image, {120, y2}, 7, kInk, cv::FILLED, cv::LINE_AA);
  DrawText(image, "registered scan", {138, y2 + 5}, 0.45, kInk);
  cv::circle(image, {300, y2}, 7, kUnregistered, 2, cv::LINE_AA);
  DrawText(image, "unregistered scan (position unknown)", {318, y2 + 5}, 0.45, kInk);
}

}  // namespace

cv::Mat DrawScanNetwork(const io::Project& project) {
  const int n = static_cast<int>(project.scans.size());
  std::vector<int> unregistered;
  Eigen::Vector2d lo(1e300, 1e300), hi(-1e300, -1e300);
  for (int i = 0; i < n; ++i) {
    if (!project.scans[i].registered) {
      unregistered.push_back(i);
      continue;
    }
    const Eigen::Vector2d p = project.scans[i].world_from_scan.translation().head<2>();
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  const bool any_registered = static_cast<int>(unregistered.size()) < n;
  const double extent = any_registered ? std::max({hi.x() - lo.x(), hi.y() - lo.y(), 1.0}) : 1.0;
  const double scale = std::min((kWidth - 2.0 * kMargin) / std::max(hi.x() - lo.x(), extent * 0.25),
                                (kMapHeight - 2.0 * kMargin) / std::max(hi.y() - lo.y(), extent * 0.25));
  const Eigen::Vector2d mid = any_registered ? Eigen::Vector2d((lo + hi) / 2) : Eigen::Vector2d::Zero();
  std::vector<cv::Point2d> at(n);
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector2d p = project.scans[i].world_from_scan.translation().head<2>();
    at[i] = {kWidth / 2.0 + (p.x() - mid.x()) * scale, kMapHeight / 2.0 - (p.y() - mid.y()) * scale};
  }
  for (std::size_t k = 0; k < unregistered.size(); ++k) {
    at[unregistered[k]] = {kMargin + (kWidth - 2.0 * kMargin) * (k + 0.5) / unregistered.size(),
                           kMapHeight + kStripHeight / 2.0 + 8};
  }

  cv::Mat image(kMapHeight + kStripHeight + kLegendHeight, kWidth, CV_8UC3, kWhite);
  cv::rectangle(image, cv::Rect(0, 0, kWidth, kMapHeight), cv::Scalar(250, 250, 250), cv::FILLED);
  if (!any_registered) {
    DrawTextCentered(image, "no scan is registered yet: register the project to place the scans",
                     {kWidth / 2, kMapHeight / 2}, 0.6, kInk);
  } else {
    const double bar = NiceLength(extent / 5);
    const cv::Point b0(kMargin, kMapHeight - 25), b1(kMargin + int(bar * scale), kMapHeight - 25);
    cv::line(image, b0, b1, kInk, 3);
    DrawText(image, LengthLabel(bar), {b0.x, b0.y - 8}, 0.5, kInk);
    DrawText(image, "top view (x right, y up)", {kWidth - 230, kMapHeight - 20}, 0.45, kInk);
  }
  if (!unregistered.empty()) {
    cv::line(image, {0, kMapHeight}, {kWidth, kMapHeight}, kGrid, 1);
    DrawText(image, "unregistered:", {10, kMapHeight + 20}, 0.45, kInk);
  }
  // Failed attempts and loop checks under the tree links, so the tree stays visible.
  for (int pass = 0; pass < 2; ++pass) {
    for (const io::LinkRecord& l : project.links) {
      const int p = project.FindScan(l.parent), c = project.FindScan(l.child);
      if (p < 0 || c < 0) continue;
      if (io::IsTreeLink(l) == (pass == 1)) DrawLink(image, at[p], at[c], l);
    }
  }
  const int root = project.root ? project.FindScan(*project.root) : -1;
  for (int i = 0; i < n; ++i) {
    const bool reg = project.scans[i].registered;
    if (reg) {
      cv::circle(image, at[i], 8, kInk, cv::FILLED, cv::LINE_AA);
    } else {
      cv::circle(image, at[i], 8, kWhite, cv::FILLED, cv::LINE_AA);
      cv::circle(image, at[i], 8, kUnregistered, 2, cv::LINE_AA);
    }
    if (i == root) cv::circle(image, at[i], 13, kInk, 2, cv::LINE_AA);
    // Unregistered scans sit in the strip, where links arrive from above: label them underneath.
    const cv::Point2d label_offset = reg ? cv::Point2d(12, -12) : cv::Point2d(-12, 30);
    DrawText(image, project.scans[i].name, cv::Point(at[i] + label_offset), 0.55, reg ? kInk : kUnregistered,
             reg ? 2 : 1);
  }
  DrawLegend(image, kMapHeight + kStripHeight);
  return image;
}

}  // namespace scanreg::report

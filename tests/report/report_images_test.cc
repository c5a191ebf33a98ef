// The report's pictures on small inputs with known content: colours where the status says, bar
// heights in proportion to the errors, the scan order of the heat map.
#include <gtest/gtest.h>

#include <opencv2/core.hpp>

#include "core/report/canvas.h"
#include "core/report/confusion_image.h"
#include "core/report/error_chart.h"
#include "core/report/network_image.h"
#include "core/io/project_tree.h"

namespace scanreg::report {
namespace {

// Pixels of exactly this BGR colour in the given rows.
int CountColour(const cv::Mat& image, const cv::Scalar& colour, int row_begin, int row_end) {
  int n = 0;
  const cv::Vec3b c(colour[0], colour[1], colour[2]);
  for (int r = row_begin; r < row_end; ++r)
    for (int k = 0; k < image.cols; ++k) n += image.at<cv::Vec3b>(r, k) == c;
  return n;
}

io::LinkRecord Link(const std::string& parent, const std::string& child, io::LinkStatus status, bool check = false) {
  io::LinkRecord l;
  l.parent = parent;
  l.child = child;
  l.status = status;
  l.loop_check = check;
  return l;
}

// a - b - c registered 10 m apart (ok, weak), d unregistered; a failed attempt c -> d.
io::Project Network(bool with_failed) {
  io::Project p;
  for (int i = 0; i < 4; ++i) {
    io::ProjectScan s;
    s.name = std::string(1, char('a' + i));
    s.registered = i < 3;
    s.world_from_scan.translation() = Eigen::Vector3d(10.0 * i, i == 2 ? 8.0 : 0.0, 0);
    p.scans.push_back(s);
  }
  p.root = "a";
  p.links = {Link("a", "b", io::LinkStatus::kOk), Link("b", "c", io::LinkStatus::kWeak)};
  if (with_failed) p.links.push_back(Link("c", "d", io::LinkStatus::kFailed));
  return p;
}

TEST(ReportImages, NetworkLinksTakeTheirStatusColours) {
  const cv::Mat with = DrawScanNetwork(Network(true));
  const cv::Mat without = DrawScanNetwork(Network(false));
  const int map_rows = with.rows - 160;  // above the unregistered strip and the legend
  EXPECT_GT(CountColour(with, StatusColor(io::LinkStatus::kOk), 0, map_rows), 500) << "ok tree link, drawn thick";
  EXPECT_GT(CountColour(with, StatusColor(io::LinkStatus::kWeak), 0, map_rows), 500) << "weak tree link";
  EXPECT_GT(CountColour(with, StatusColor(io::LinkStatus::kFailed), 0, with.rows - 70), 20) << "failed attempt";
  EXPECT_EQ(CountColour(without, StatusColor(io::LinkStatus::kFailed), 0, without.rows - 70), 0);
  // The legend shows every status either way.
  EXPECT_GT(CountColour(without, StatusColor(io::LinkStatus::kFailed), without.rows - 70, without.rows), 0);
}

TEST(ReportImages, LoopChecksAreDrawnThinnerThanTreeLinks) {
  io::Project tree = Network(false);
  io::Project check = tree;
  check.links = {Link("a", "b", io::LinkStatus::kOk, true), Link("b", "c", io::LinkStatus::kWeak)};
  const int rows = DrawScanNetwork(tree).rows - 160;
  const int as_tree = CountColour(DrawScanNetwork(tree), StatusColor(io::LinkStatus::kOk), 0, rows);
  const int as_check = CountColour(DrawScanNetwork(check), StatusColor(io::LinkStatus::kOk), 0, rows);
  EXPECT_GT(as_check, 0);
  EXPECT_LT(as_check * 3, as_tree) << "a dotted 2 px loop check against a solid 5 px tree link";
}

TEST(ReportImages, ErrorBarsAreInProportionToTheErrors) {
  std::vector<pipeline::ReferenceError> errors(2);
  for (auto& e : errors) {
    e.available = e.has_coarse = true;
    e.coarse_angle_rad = e.angle_rad = 0.001;
  }
  errors[0].coarse_position_m = 0.040;  // 4 x the fine error
  errors[0].position_m = 0.010;
  const cv::Mat chart = DrawReferenceErrorChart({"s01", "s02"}, errors);
  const int panel = (chart.rows - 40) / 2;
  const cv::Scalar coarse(230, 190, 140), fine(140, 70, 20);
  const double ratio = double(CountColour(chart, coarse, 0, panel)) / CountColour(chart, fine, 0, panel);
  EXPECT_NEAR(ratio, 4.0, 0.15);
  // Equal angle errors: equal bars in the lower panel.
  const double angle_ratio =
      double(CountColour(chart, coarse, panel, 2 * panel)) / CountColour(chart, fine, panel, 2 * panel);
  EXPECT_NEAR(angle_ratio, 1.0, 0.05);
}

TEST(ReportImages, HeatMapGrowsWithTheScansAndShadesTheStrongestPairDarkest) {
  Eigen::MatrixXi c(3, 3);
  c << 900, 10, 0, 10, 950, 300, 0, 280, 870;
  const cv::Mat small = DrawConfusionHeatMap(c, {"a", "b", "c"});
  EXPECT_GT(CountColour(small, cv::Scalar(255, 102, 51), 0, small.rows), 100) << "the 300 cell in deep blue";
  EXPECT_GT(CountColour(small, cv::Scalar(210, 210, 210), 0, small.rows), 300) << "the diagonal in grey";
  const Eigen::MatrixXi big = Eigen::MatrixXi::Constant(6, 6, 5);
  EXPECT_GT(DrawConfusionHeatMap(big, {"a", "b", "c", "d", "e", "f"}).cols, small.cols);
}

TEST(ReportImages, ScanOrderFollowsTheTreeFromTheRoot) {
  io::Project p = Network(true);
  p.root = "b";
  p.links = {Link("b", "c", io::LinkStatus::kOk), Link("b", "a", io::LinkStatus::kWeak),
             Link("c", "d", io::LinkStatus::kFailed)};
  EXPECT_EQ(io::OrderedScanIndices(p), (std::vector<int>{1, 2, 0, 3}));
  EXPECT_FALSE(io::IsTreeLink(p.links[2]));
  p.links[0].user_rejected = true;
  EXPECT_EQ(io::OrderedScanIndices(p), (std::vector<int>{1, 0, 2, 3}));
}

}  // namespace
}  // namespace scanreg::report

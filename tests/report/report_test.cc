// The registration report on a simulated project registered end to end (true poses known): its
// sections and tables, its pictures, its error figures against the truth, and its errors.
#include "core/report/report.h"

#include <gtest/gtest.h>

#include <fstream>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <regex>
#include <set>
#include <sstream>

#include "core/pipeline/create_project.h"
#include "core/pipeline/project_edits.h"
#include "core/pipeline/project_scans.h"
#include "core/pipeline/register_project.h"
#include "core/report/html_table.h"
#include "tests/io/io_test_util.h"
#include "tests/support/test_paths.h"

namespace scanreg::report {
namespace {

// The text of <table id="id"> ... </table>, empty when absent.
std::string Table(const std::string& html, const std::string& id) {
  const std::size_t begin = html.find("<table id=\"" + id + "\">");
  if (begin == std::string::npos) return "";
  return html.substr(begin, html.find("</table>", begin) - begin);
}

// The cells of each body row of a table, as text.
std::vector<std::vector<std::string>> Rows(const std::string& table) {
  std::vector<std::vector<std::string>> rows;
  const std::string body = table.substr(std::min(table.find("<tbody>"), table.size()));
  const std::regex row("<tr[^>]*>([\\s\\S]*?)</tr>"), cell("<td>([\\s\\S]*?)</td>");
  for (auto r = std::sregex_iterator(body.begin(), body.end(), row); r != std::sregex_iterator(); ++r) {
    const std::string inner = (*r)[1];
    std::vector<std::string> cells;
    for (auto c = std::sregex_iterator(inner.begin(), inner.end(), cell); c != std::sregex_iterator(); ++c)
      cells.push_back((*c)[1]);
    rows.push_back(cells);
  }
  return rows;
}

std::vector<std::string> ImageSources(const std::string& html) {
  std::vector<std::string> sources;
  const std::regex img("<img src=\"([^\"]+)\"");
  for (auto m = std::sregex_iterator(html.begin(), html.end(), img); m != std::sregex_iterator(); ++m)
    sources.push_back((*m)[1]);
  return sources;
}

// Small pictures of real content: decodes, not one flat colour, several colours.
void ExpectPicture(const std::filesystem::path& file) {
  const cv::Mat image = cv::imread(file.string(), cv::IMREAD_COLOR);
  ASSERT_FALSE(image.empty()) << file;
  EXPECT_GT(image.cols, 200) << file;
  cv::Mat gray;
  cv::cvtColor(image, gray, cv::COLOR_BGR2GRAY);
  cv::Scalar mean, stddev;
  cv::meanStdDev(gray, mean, stddev);
  EXPECT_GT(stddev[0], 10.0) << file << " looks blank";
  std::set<int> colours;
  for (int r = 0; r < image.rows; r += 3)
    for (int c = 0; c < image.cols; c += 3) {
      const cv::Vec3b p = image.at<cv::Vec3b>(r, c);
      colours.insert(p[0] << 16 | p[1] << 8 | p[2]);
    }
  EXPECT_GT(colours.size(), 3u) << file << " has almost one colour";
}

SimulatedProjectOptions Street(int stations, int cols, int rows) {
  SimulatedProjectOptions o;
  o.stations = stations;
  o.spacing_m = 4;
  o.scanner.cols = cols;
  o.scanner.rows = rows;
  o.seed = o.scanner.seed = o.scene.seed = 2;
  o.add_far_station = true;
  return o;
}

// One end-to-end run (registration takes seconds): 2 stations 4 m apart and one far station
// that cannot be registered, registered, saved, loaded back and reported.
TEST(Report, RegisteredProjectShowsItsEvidenceAndTheErrorsAgainstTheTruth) {
  test::TempDir dir;
  NullProgress progress;
  CancelToken cancel;
  Expected<io::Project> project = pipeline::WriteSimulatedProject(Street(2, 1200, 300), dir / "p", progress, cancel);
  ASSERT_TRUE(project.ok()) << project.error().ToString();
  auto scans = pipeline::LoadProjectScans(*project, progress, cancel);
  ASSERT_TRUE(scans.ok()) << scans.error().ToString();
  auto result = pipeline::RegisterProjectScans(*project, *scans, pipeline::RegisterOptions{}, progress, cancel);
  ASSERT_TRUE(result.ok()) << result.error().ToString();
  const std::vector<pipeline::ReferenceError> truth = pipeline::ReferenceErrors(*result, *scans);
  ASSERT_TRUE(io::SaveProject(*project, project->file).ok());
  Expected<io::Project> loaded = io::LoadProject(project->file);
  ASSERT_TRUE(loaded.ok()) << loaded.error().ToString();

  // The saved project keeps what the report needs: the confusion matrix and the coarse poses.
  ASSERT_NE(loaded->CurrentConfusion(), nullptr);
  ASSERT_EQ(loaded->CurrentConfusion()->rows(), 3);
  EXPECT_TRUE(*loaded->CurrentConfusion() == result->confusion);
  EXPECT_GT(result->confusion(0, 1), 0);
  ASSERT_FALSE(loaded->scans[2].registered);
  EXPECT_FALSE(loaded->scans[2].unregistered_reason.empty());
  const std::vector<pipeline::ReferenceError> saved = pipeline::ReferenceErrors(*loaded);
  ASSERT_EQ(saved.size(), truth.size());
  for (std::size_t i = 0; i < saved.size(); ++i) {
    EXPECT_EQ(saved[i].available, truth[i].available) << i;
    EXPECT_NEAR(saved[i].position_m, truth[i].position_m, 1e-9) << i;
    EXPECT_NEAR(saved[i].angle_rad, truth[i].angle_rad, 1e-9) << i;
    EXPECT_EQ(saved[i].has_coarse, truth[i].has_coarse) << i;
    EXPECT_NEAR(saved[i].coarse_position_m, truth[i].coarse_position_m, 1e-9) << i;
  }

  Expected<std::filesystem::path> index = WriteReport(*loaded, dir / "report", progress, cancel);
  ASSERT_TRUE(index.ok()) << index.error().ToString();
  const std::string html = test::ReadBytes(*index);
  for (const char* id : {"summary", "confusion", "network", "links", "poses", "errors"})
    EXPECT_NE(html.find(std::string("id=\"") + id + "\""), std::string::npos) << id;
  EXPECT_EQ(html.find("not-registered"), std::string::npos);
  EXPECT_EQ(html.find("http"), std::string::npos) << "the page must not reach the network";
  ASSERT_GE(loaded->links.size(), 2u) << "a tree link and failed attempts to the far station";
  EXPECT_EQ(Rows(Table(html, "links-table")).size(), loaded->links.size());
  const auto poses = Rows(Table(html, "poses-table"));
  ASSERT_EQ(poses.size(), 3u);
  EXPECT_NE(poses[2][1].find("not registered: "), std::string::npos) << poses[2][1];
  for (std::size_t i = 0; i < 2; ++i) {
    EXPECT_NEAR(std::stod(poses[i][2]), loaded->scans[i].world_from_scan.translation().x(), 0.0001);
    EXPECT_NEAR(std::stod(poses[i][4]), loaded->scans[i].world_from_scan.translation().z(), 0.0001);
  }
  int registered = -1, unregistered = -1;
  for (const auto& row : Rows(Table(html, "summary-table"))) {
    if (row[0] == "registered") registered = std::stoi(row[1]);
    if (row[0] == "not registered") unregistered = std::stoi(row[1]);
  }
  EXPECT_EQ(registered, 2);
  EXPECT_EQ(unregistered, 1);
  EXPECT_NE(Table(html, "settings-table").find("simulated.stations"), std::string::npos);
  // The heat map's scan order starts at the root; the far station comes last.
  const std::string span = "<span id=\"scan-order\">";
  const std::size_t order = html.find(span);
  ASSERT_NE(order, std::string::npos);
  EXPECT_EQ(html.substr(order + span.size(), loaded->root->size()), *loaded->root);
  EXPECT_EQ(html.substr(html.find("</span>", order) - 3, 3), loaded->scans[2].name);

  // W fig. 6 table: the errors against the true poses, as computed at registration.
  const auto errors = Rows(Table(html, "errors-table"));
  ASSERT_EQ(errors.size(), 3u);
  for (int i = 0; i < 2; ++i) {
    ASSERT_TRUE(truth[i].available) << i;
    ASSERT_EQ(errors[i].size(), 5u);
    const double fine_mm = std::stod(errors[i][2]);
    EXPECT_NEAR(fine_mm, truth[i].position_m * 1000, 0.051) << errors[i][0];
    EXPECT_LT(fine_mm, 30.0) << errors[i][0] << ": registered within 3 cm of the true pose";
    EXPECT_NEAR(std::stod(errors[i][4]), truth[i].angle_rad * 180 / M_PI, 0.0001) << errors[i][0];
  }
  const int child = result->root == 0 ? 1 : 0;
  ASSERT_TRUE(truth[child].has_coarse);
  EXPECT_NEAR(std::stod(errors[child][1]), truth[child].coarse_position_m * 1000, 0.051);
  EXPECT_EQ(errors[2][2], "-") << "the far station has no error";

  const std::vector<std::string> sources = ImageSources(html);
  EXPECT_EQ(sources, (std::vector<std::string>{kConfusionPng, kNetworkPng, kErrorsPng}));
  for (const std::string& src : sources) ExpectPicture(dir / "report" / src);
}

TEST(Report, UnregisteredProjectGivesAReportThatSaysSo) {
  test::TempDir dir;
  NullProgress progress;
  CancelToken cancel;
  Expected<io::Project> project = pipeline::WriteSimulatedProject(Street(2, 300, 80), dir / "p", progress, cancel);
  ASSERT_TRUE(project.ok()) << project.error().ToString();
  Expected<std::filesystem::path> index = WriteReport(*project, dir / "report", progress, cancel);
  ASSERT_TRUE(index.ok()) << index.error().ToString();
  const std::string html = test::ReadBytes(*index);
  EXPECT_NE(html.find("id=\"not-registered\""), std::string::npos);
  EXPECT_NE(html.find("has not been registered"), std::string::npos);
  EXPECT_EQ(Rows(Table(html, "links-table")).size(), 0u);
  EXPECT_EQ(Rows(Table(html, "poses-table")).size(), 3u);
  EXPECT_EQ(ImageSources(html), std::vector<std::string>{kNetworkPng});
  ExpectPicture(dir / "report" / kNetworkPng);
}

TEST(Report, AScanPlacedByHandIsMarkedAsHavingNoLinkEvidence) {
  test::TempDir dir;
  NullProgress progress;
  CancelToken cancel;
  Expected<io::Project> project = pipeline::WriteSimulatedProject(Street(2, 300, 80), dir / "p", progress, cancel);
  ASSERT_TRUE(project.ok()) << project.error().ToString();
  project->root = project->scans[0].name;
  project->scans[0].registered = true;
  ASSERT_TRUE(pipeline::SetScanPose(project->scans[1].name, project->scans[1].world_from_scan, false, *project).ok());
  Expected<std::filesystem::path> index = WriteReport(*project, dir / "report", progress, cancel);
  ASSERT_TRUE(index.ok()) << index.error().ToString();
  const auto poses = Rows(Table(test::ReadBytes(*index), "poses-table"));
  ASSERT_EQ(poses.size(), 3u);
  EXPECT_EQ(poses[0][1], "root");
  EXPECT_EQ(poses[1][1], "placed by hand (no link evidence)");
  EXPECT_NE(poses[2][1].find("not registered"), std::string::npos);
  // A scan the registration placed but could not verify is told apart from one it could not place.
  project->scans[2].unverified = true;
  project->scans[2].unregistered_reason = "not verified: placed only by a weak link from s02";
  index = WriteReport(*project, dir / "report2", progress, cancel);
  ASSERT_TRUE(index.ok()) << index.error().ToString();
  const auto again = Rows(Table(test::ReadBytes(*index), "poses-table"));
  ASSERT_EQ(again.size(), 3u);
  EXPECT_EQ(again[2][1], "not verified, kept at its start pose: placed only by a weak link from s02")
      << again[2][1];
}

TEST(Report, FixedNumbersNeverShowANegativeZero) {
  EXPECT_EQ(Fixed(-0.00002, 1), "0.0");
  EXPECT_EQ(Fixed(-0.04, 1), "0.0");
  EXPECT_EQ(Fixed(-0.06, 1), "-0.1");
  EXPECT_EQ(Fixed(2.345, 2), "2.35");
  EXPECT_EQ(Fixed(-3.0, 0), "-3");
}

TEST(Report, AFileOrAnUnwritablePlaceIsAClearError) {
  test::TempDir dir;
  { std::ofstream(dir / "a_file") << "x"; }
  io::Project project;
  project.file = dir / "p.scanreg.json";
  project.scans.resize(2);
  project.scans[0].name = "a";
  project.scans[1].name = "b";
  NullProgress progress;
  CancelToken cancel;
  Expected<std::filesystem::path> onto_file = WriteReport(project, dir / "a_file", progress, cancel);
  ASSERT_FALSE(onto_file.ok());
  EXPECT_NE(onto_file.error().message.find("a_file"), std::string::npos) << onto_file.error().message;
  EXPECT_NE(onto_file.error().message.find("folder"), std::string::npos) << onto_file.error().message;
  Expected<std::filesystem::path> below_file = WriteReport(project, dir / "a_file" / "report", progress, cancel);
  ASSERT_FALSE(below_file.ok());
  EXPECT_NE(below_file.error().message.find("a_file"), std::string::npos) << below_file.error().message;
  EXPECT_EQ(test::ReadBytes(dir / "a_file"), "x") << "the file is left alone";
  CancelToken cancelled;
  cancelled.Cancel();
  Expected<std::filesystem::path> stopped = WriteReport(project, dir / "r", progress, cancelled);
  ASSERT_FALSE(stopped.ok());
  EXPECT_EQ(stopped.error().code, ErrorCode::kCancelled);
  EXPECT_FALSE(std::filesystem::exists(dir / "r" / "index.html"));
  // The same project in a writable folder is fine.
  EXPECT_TRUE(WriteReport(project, dir / "ok", progress, cancel).ok());
}

}  // namespace
}  // namespace scanreg::report

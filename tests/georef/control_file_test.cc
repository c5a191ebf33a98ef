#include "core/io/control_file.h"

#include <gtest/gtest.h>

#include <fstream>

#include "tests/support/test_paths.h"

namespace scanreg::io {
namespace {

std::filesystem::path Write(const test::TempDir& dir, const std::string& text) {
  const auto path = dir / "control.csv";
  std::ofstream(path, std::ios::binary) << text;
  return path;
}

TEST(ControlFile, ReadsTheSeparatorsSurveySoftwareWrites) {
  test::TempDir dir;
  auto points = ReadControlFile(Write(dir,
                                      "# site control, ETRS89 / UTM 32N\n"
                                      "Point,Easting,Northing,Height,Sigma\r\n"
                                      "CP1,512345.6789,5401234.5678,102.345,0.002\r\n"
                                      "CP2; 512400.0; 5401200.25; 101.5\n"
                                      "\"CP 3\"\t512380.125\t5401260.5\t103\t0.004\n"
                                      "\n"
                                      "CP4 512300 5401300 99.875\n"));
  ASSERT_TRUE(points.ok()) << points.error().message;
  ASSERT_EQ(points->size(), 4u);
  EXPECT_EQ((*points)[0].name, "CP1");
  EXPECT_DOUBLE_EQ((*points)[0].position.x(), 512345.6789);
  EXPECT_DOUBLE_EQ((*points)[0].position.y(), 5401234.5678);
  EXPECT_DOUBLE_EQ((*points)[0].position.z(), 102.345);
  EXPECT_DOUBLE_EQ(*(*points)[0].sigma_m, 0.002);
  EXPECT_FALSE((*points)[1].sigma_m.has_value());
  EXPECT_DOUBLE_EQ((*points)[1].position.y(), 5401200.25);
  EXPECT_EQ((*points)[2].name, "CP 3");
  EXPECT_DOUBLE_EQ(*(*points)[2].sigma_m, 0.004);
  EXPECT_DOUBLE_EQ((*points)[3].position.z(), 99.875);
}

TEST(ControlFile, BadLinesAreNamedWithTheirLine) {
  test::TempDir dir;
  struct Case {
    std::string text, expect;
  };
  for (const Case& c : {Case{"CP1,1,2\n", "line 1"}, Case{"CP1,1,2,3\nCP2,1,nan,3\n", "line 2"},
                        Case{"CP1,1,2,3\nCP1,4,5,6\n", "given twice"}, Case{"CP1,1,2,3,-0.1\n", "sigma"},
                        Case{"# nothing\n", "no control point"}, Case{"CP1,1,2,3,4,5,6\n", "7 fields"},
                        Case{"\"CP1,1,2,3\n", "quote"}}) {
    auto points = ReadControlFile(Write(dir, c.text));
    ASSERT_FALSE(points.ok()) << c.text;
    EXPECT_NE(points.error().message.find(c.expect), std::string::npos) << points.error().message;
    EXPECT_NE(points.error().message.find("control.csv"), std::string::npos) << points.error().message;
  }
  EXPECT_FALSE(ReadControlFile(dir.path()).ok()) << "a directory";
  EXPECT_FALSE(ReadControlFile(dir / "missing.csv").ok());
}

}  // namespace
}  // namespace scanreg::io

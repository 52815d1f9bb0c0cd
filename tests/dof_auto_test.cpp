// `auto`: the method table's CSV form (parsing, errors naming the line, round trip), the choice
// rule on hand-made tables whose right answer is worked out here by hand, and the table that
// is compiled in (every registered method has rows, so `auto` can consider them all).
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>

#include "test_util.hpp"
#include "tridiff/dof/auto.hpp"

namespace tridiff {
namespace {

using testing_util::make_coc;
using testing_util::random_image;

MethodTableRow row(std::string method, std::string scene, bool near, float radius,
                   double work_fraction, double seconds, double psnr) {
  MethodTableRow r;
  r.method = std::move(method);
  r.scene = std::move(scene);
  r.width = r.height = 100;
  r.threads = 2;
  r.max_radius = radius;
  r.has_near = near;
  r.work_fraction = work_fraction;
  r.seconds = seconds;
  r.psnr = psnr;
  r.ssim = 0.9;
  return r;
}

// A 100 x 100 frame whose left half is far and blurred (radius 4), the right half sharp.
Image far_half_coc() {
  return make_coc(100, 100, [](auto x, auto) { return x < 50 ? 8.f : 0.f; });
}

TEST(DofAuto, TableRoundTripsThroughCsv) {
  std::vector<MethodTableRow> rows = {
      row("adi", "a", false, 4, 0.5, 0.01, 31.5),
      row("scatter", "a", true, 16, 1, 2.5, std::numeric_limits<double>::infinity())};
  rows[0].reference = "truth";
  const std::vector<MethodTableRow> back = parse_method_table(format_method_table(rows));
  ASSERT_EQ(back.size(), 2u);
  EXPECT_EQ(back[0].method, "adi");
  EXPECT_EQ(back[0].max_radius, 4.f);
  EXPECT_FALSE(back[0].has_near);
  EXPECT_DOUBLE_EQ(back[0].psnr, 31.5);
  EXPECT_EQ(back[0].reference, "truth");
  EXPECT_EQ(back[1].reference, "scatter");
  EXPECT_TRUE(back[1].has_near);
  EXPECT_TRUE(std::isinf(back[1].psnr));
}

TEST(DofAuto, MalformedTableNamesTheLine) {
  const std::string header =
      "method,scene,width,height,threads,max_radius,has_near,work_fraction,seconds,psnr,ssim,"
      "reference\n";
  for (const auto& [csv, line] : std::vector<std::pair<std::string, std::ptrdiff_t>>{
           {"method,scene\n", 1},
           {"# comment\n" + header + "adi,a,100,100,2,4,0,0.5,0.01,31\n", 3},
           {header + "adi,a,100,100,2,4,2,0.5,0.01,31,0.9,truth\n", 2},
           {header + "adi,a,100,100,2,4,0,0.5,fast,31,0.9,truth\n", 2},
           {header + "adi,a,100,100,2,4,0,1.5,0.01,31,0.9,truth\n", 2},
           {header + "adi,a,100,100,2,4,0,0.5,0.01,31,0.9,dense\n", 2},
           {"", 1}}) {
    try {
      parse_method_table(csv);
      ADD_FAILURE() << "accepted: " << csv;
    } catch (const InvalidArgument& e) {
      EXPECT_EQ(e.argument(), "table");
      EXPECT_NE(std::string(e.what()).find("line " + std::to_string(line)), std::string::npos)
          << e.what();
    }
  }
}

TEST(DofAuto, ChoosesTheCheapestMethodWithinTheBudget) {
  // Far-only frame: the far rows are the like ones. adi: 10 ms on a row with the same work,
  // 29 dB (over a 30 dB budget); ipf: 40 ms, 33 dB; scatter: 1 s, exact.
  const std::vector<MethodTableRow> table = {
      row("adi", "far", false, 4, 0.64, 0.010, 29),
      row("adi", "near", true, 4, 0.64, 0.010, 20),  // not like the frame: ignored
      row("ipf", "far", false, 4, 0.64, 0.040, 33),
      row("scatter", "far", false, 4, 0.64, 1.0, std::numeric_limits<double>::infinity())};
  const Image coc = far_half_coc();
  DofOptions settings;
  settings.error_budget_psnr = 30;
  MethodChoice choice = choose_dof_method(coc.plane(0), settings, table);
  EXPECT_EQ(choice.method, "ipf");
  EXPECT_TRUE(choice.meets_budget);
  EXPECT_DOUBLE_EQ(choice.expected_psnr, 33);
  // Worked pixels: columns 0..63 (two 32-px tiles; radius 4 reaches 5 px past x = 49) of 100:
  // 64 %, as in the row, and the same radius: the row's time.
  EXPECT_NEAR(choice.predicted_seconds, 0.040, 1e-12);
  EXPECT_NE(choice.reason.find("Chose ipf"), std::string::npos) << choice.reason;
  EXPECT_NE(choice.reason.find("mpad"), std::string::npos);  // registered, not in the table

  settings.error_budget_psnr = 28;  // now adi qualifies and is cheaper
  EXPECT_EQ(choose_dof_method(coc.plane(0), settings, table).method, "adi");
  settings.error_budget_psnr = 1e9;  // nothing but the exact reference
  EXPECT_EQ(choose_dof_method(coc.plane(0), settings, table).method, "scatter");
}

TEST(DofAuto, NoMethodWithinBudgetPicksTheMostAccurate) {
  const std::vector<MethodTableRow> table = {row("adi", "far", false, 4, 0.64, 0.01, 25),
                                             row("ipf", "far", false, 4, 0.64, 0.04, 27)};
  DofOptions settings;
  settings.error_budget_psnr = 40;
  const MethodChoice choice = choose_dof_method(far_half_coc().plane(0), settings, table);
  EXPECT_EQ(choice.method, "ipf");
  EXPECT_FALSE(choice.meets_budget);
}

TEST(DofAuto, CostScalesWithWorkAndForBoundedMethodsWithTheRadiusSquared) {
  // Row measured on a 2x smaller radius and a quarter of the work. adi's cost does not grow with
  // the CoC (unbounded_blur): x 0.64 / 0.16 = 4. ipf's does: x 4 x (4 / 2)^2 = 16.
  const std::vector<MethodTableRow> table = {row("adi", "far", false, 2, 0.16, 0.01, 35),
                                             row("ipf", "far", false, 2, 0.16, 0.01, 35)};
  DofOptions settings;
  const MethodChoice choice = choose_dof_method(far_half_coc().plane(0), settings, table);
  EXPECT_EQ(choice.method, "adi");
  EXPECT_NEAR(choice.predicted_seconds, 0.04, 1e-12);
  EXPECT_NE(choice.reason.find("ipf (160 ms"), std::string::npos) << choice.reason;
}

// `auto` chooses from the frame's tiles (analysed once, then handed to the chosen method): the
// same choice as from the CoC map itself.
TEST(DofAuto, ChoiceFromTheFrameTilesIsTheChoiceFromTheCoc) {
  const Image coc = far_half_coc();
  for (const double budget : {10.0, 30.0, 60.0}) {
    DofOptions settings;
    settings.error_budget_psnr = budget;
    const TileMap tiles(coc.plane(0), sharp_below_px(settings.in_focus_coc_px));
    const MethodChoice a = choose_dof_method(coc.plane(0), settings, builtin_method_table());
    const MethodChoice b = choose_dof_method(tiles, settings, builtin_method_table());
    EXPECT_EQ(a.method, b.method);
    EXPECT_EQ(a.reason, b.reason);
  }
}

TEST(DofAuto, TableWithoutRegisteredMethodsIsRejected) {
  const std::vector<MethodTableRow> table = {row("nonesuch", "far", false, 2, 0.5, 0.01, 35)};
  EXPECT_THROW(choose_dof_method(far_half_coc().plane(0), {}, table), InvalidArgument);
}

TEST(DofAuto, BuiltinTableCoversEveryRegisteredMethod) {
  const std::span<const MethodTableRow> table = builtin_method_table();
  for (const DofMethod& method : dof_methods()) {
    if (method.name == "auto") continue;
    std::size_t rows = 0;
    for (const MethodTableRow& r : table) rows += r.method == method.name;
    EXPECT_GE(rows, 3u) << method.name << ": regenerate with scripts/dof_method_table.sh";
  }
}

TEST(DofAuto, RunsTheChosenMethodAndSaysSo) {
  const Image color = random_image(100, 100, 3, 0.f, 1.f, 5);
  const Image coc = far_half_coc();
  Image out;
  DofReport report;
  report = depth_of_field(out, color, coc.plane(0), find_dof_method("auto"), {});
  ASSERT_FALSE(report.chosen_method.empty());
  EXPECT_NE(report.notes.find("Chose " + report.chosen_method), std::string::npos);
  Image direct;
  DofReport direct_report;
  direct_report =
      depth_of_field(direct, color, coc.plane(0), find_dof_method(report.chosen_method), {});
  for (int c = 0; c < 3; ++c)
    for (std::ptrdiff_t y = 0; y < 100; ++y)
      for (std::ptrdiff_t x = 0; x < 100; ++x)
        ASSERT_TRUE(testing_util::same_bits(out(x, y, c), direct(x, y, c)));
}

}  // namespace
}  // namespace tridiff

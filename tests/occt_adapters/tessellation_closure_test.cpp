// A closed solid's tessellation is a closed mesh — per solid, so that the kernel can find what lies
// inside it: poles and apexes leave no segment-triangles, and solids of an assembly that share
// edges stay separate closed bodies (merged, their shared edges had four triangles each, and a
// part nested in any of them was answered CLEAR).
#include "occt_adapters/shape_import.h"
#include "occt_adapters/shape_mesher.h"
#include "tests/support/random_meshes.h"

#include <gtest/gtest.h>

#include <chrono>

namespace gk {
namespace {

TEST(TessellationClosure, EverySolidOfTheSharedCadPartsIsAClosedBody) {
  struct Case {
    const char* file;
    std::size_t solids;
  };
  for (const Case& c : {Case{"step/occt/screw.step", 1}, Case{"step/occt/linkrods.step", 1}, Case{"step/occt/Pump_Nut.brep", 1},
                        Case{"step/occt/Pump_TopCover.brep", 1}, Case{"step/occt/bottle.brep", 1},
                        Case{"step/gmsh/as1-tu-203.stp", 18},
                        Case{"step/sheetmetal/Heatsink_AAVID_573300D00010G_TO-263.step", 1}}) {
    SCOPED_TRACE(c.file);
    auto shape = occt::read_shape_file(testing::shared_data(c.file));
    ASSERT_TRUE(shape.ok()) << shape.error().to_string();
    EXPECT_EQ(static_cast<std::size_t>(shape.value().solid_count()), c.solids);
    for (double deflection : {0.05, 0.5}) {
      auto meshed = occt::mesh_shape(shape.value(), deflection);
      ASSERT_TRUE(meshed.ok()) << meshed.error().to_string();
      const MeshReport& r = meshed.value().mesh.report();
      EXPECT_TRUE(r.closed && r.consistently_oriented)
          << "boundary edges " << r.boundary_edges << ", non-manifold " << r.non_manifold_edges;
      EXPECT_EQ(meshed.value().mesh.body_seeds().size(), c.solids);
      EXPECT_TRUE(r.zero_area_triangles.empty());
    }
  }
}

}  // namespace
}  // namespace gk

namespace gk {
namespace {

// A few bytes declaring two billion table entries kept OCCT's BREP reader busy for 12 s: refused
// before it runs (issue: hardened service §3).
TEST(BrepImport, AbsurdTableCountsAreRefusedAtOnce) {
  const std::string header = "DBRep_DrawableShape\n\nCASCADE Topology V1, (c) Matra-Datavision\n";
  for (const char* table : {"Locations 2000000000", "Curves 999999999", "TShapes 123456789"}) {
    const auto t0 = std::chrono::steady_clock::now();
    auto read = occt::read_shape_bytes(header + table + "\n", "brep");
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    ASSERT_FALSE(read.ok());
    EXPECT_NE(read.error().message.find("declares"), std::string::npos) << read.error().to_string();
    EXPECT_LT(s, 1.0);
  }
}

}  // namespace
}  // namespace gk

// The IFC importer on the real samples: the products with geometry (openings, spaces and
// annotations not drawn) as counted from the files' text, one database key (GlobalId) each;
// parametric geometry kept (the MEP pipes and bends, the CSG block); the three basic shapes, one
// solid written three ways, in the same place; and the Part 21 reader's errors on damaged text.
#include <gtest/gtest.h>

#include <map>
#include <numbers>
#include <set>

#include "format_error.h"
#include "ifc_importer.h"
#include "profile_prism.h"
#include "steel_profiles.h"
#include "step21_file.h"
#include "tessellate.h"
#include "test_support.h"

namespace tw {
namespace {

namespace fs = std::filesystem;

fs::path sample(const char* name) { return test::sharedDataDir() / name; }

test::CollectingSink import(const fs::path& path, std::vector<std::string>* warnings = nullptr) {
  test::CollectingSink sink;
  ReadOptions options;
  options.warn = [warnings](const std::string& w) {
    if (warnings) warnings->push_back(w);
  };
  readIfc(path, sink, options);
  return sink;
}

std::set<std::string> keys(const test::CollectingSink& sink) {
  std::set<std::string> k;
  for (const SceneObject& o : sink.objects) k.insert(o.info.db_key);
  return k;
}

void worldBounds(const test::CollectingSink& sink, glm::dvec3& lo, glm::dvec3& hi) {
  lo = glm::dvec3(1e300);
  hi = glm::dvec3(-1e300);
  for (const SceneObject& o : sink.objects) {
    TriangleMesh mesh;
    tessellate(o.geometry, 0.001f, mesh);
    for (const glm::vec3& p : mesh.positions) {
      lo = glm::min(lo, o.info.transform.apply(p));
      hi = glm::max(hi, o.info.transform.apply(p));
    }
  }
}

// Products with a representation, by class, counted from the text (a Part 21 instance whose
// first argument is a 22-character GlobalId and whose seventh is a reference), less openings,
// spaces and annotations: TestModel 4 walls, 2 slabs, 2 doors, 7 windows, a stair flight, 2
// members, 2 railings; acad2010 11 walls, 4 windows, 7 doors, a curtain wall, a roof, 8 columns,
// 4 beams, a member, 2 stairs, 2 railings, 11 proxies; bcf-architectural 20 coverings, a slab, a
// proxy, 14 walls, a door, a window, 25 members, 12 plates.
TEST(IfcImport, EveryProductWithGeometryComesInWithItsGlobalId) {
  const std::map<std::string, size_t> expected = {
      {"TestModel_IFC4Add2.ifc", 20}, {"acad2010_objects.ifc", 52}, {"bcf-architectural.ifc", 75},
      {"bcf-mep.ifc", 8},            {"cylinders.ifc", 4},         {"basic_shape_Brep.ifc", 1},
      {"basic_shape_CSG.ifc", 1},    {"basic_shape_SweptSolid.ifc", 1}};
  for (const auto& [file, products] : expected) {
    const test::CollectingSink sink = import(sample(file.c_str()));
    const std::set<std::string> k = keys(sink);
    EXPECT_EQ(k.size(), products) << file;
    for (const std::string& key : k) EXPECT_EQ(key.size(), 22u) << file << ": " << key;
    glm::dvec3 lo, hi;
    worldBounds(sink, lo, hi);
    EXPECT_LT(glm::length(hi - lo), 200.0) << file << ": metres, not millimetres";
  }
}

TEST(IfcImport, OneSolidWrittenAsBrepCsgAndSweptSolidLandsInOnePlace) {
  for (const char* file : {"basic_shape_Brep.ifc", "basic_shape_CSG.ifc", "basic_shape_SweptSolid.ifc"}) {
    const test::CollectingSink sink = import(sample(file));
    glm::dvec3 lo, hi;
    worldBounds(sink, lo, hi);
    EXPECT_NEAR(lo.x, 0.5, 1e-6) << file;
    EXPECT_NEAR(lo.y, -0.5, 1e-6) << file;
    EXPECT_NEAR(lo.z, 0.0, 1e-6) << file;
    EXPECT_NEAR(hi.x, 1.5, 1e-6) << file;
    EXPECT_NEAR(hi.y, 0.5, 1e-6) << file;
    EXPECT_NEAR(hi.z, 2.0, 1e-6) << file;
  }
  // The CSG block and the extruded rectangle stay boxes; the B-rep is a mesh.
  EXPECT_TRUE(std::holds_alternative<Primitive>(import(sample("basic_shape_CSG.ifc")).objects[0].geometry));
  EXPECT_TRUE(std::holds_alternative<Primitive>(import(sample("basic_shape_SweptSolid.ifc")).objects[0].geometry));
  EXPECT_TRUE(std::holds_alternative<TriangleMesh>(import(sample("basic_shape_Brep.ifc")).objects[0].geometry));
}

TEST(IfcImport, PipesAndBendsStayParametric) {
  const test::CollectingSink sink = import(sample("bcf-mep.ifc"));
  std::map<size_t, int> kinds;
  for (const SceneObject& o : sink.objects) {
    const auto* p = std::get_if<Primitive>(&o.geometry);
    ASSERT_NE(p, nullptr) << o.info.name << ": every MEP item is a primitive";
    kinds[p->index()]++;
  }
  EXPECT_EQ(kinds[0], 5) << "extruded hollow circles: cylinders";
  EXPECT_EQ(kinds[3], 3) << "revolved hollow circles: torus segments";
  for (const SceneObject& o : sink.objects)
    if (const auto* t = std::get_if<TorusSegment>(&std::get<Primitive>(o.geometry))) {
      EXPECT_GT(t->major_radius, t->minor_radius);
      EXPECT_GT(t->sweep_rad, 0.1f);
      EXPECT_LE(t->sweep_rad, 6.2832f);
    }
  const test::CollectingSink cylinders = import(sample("cylinders.ifc"));
  for (const SceneObject& o : cylinders.objects)
    EXPECT_TRUE(std::holds_alternative<Cylinder>(std::get<Primitive>(o.geometry))) << o.info.name;
}

TEST(IfcImport, LayersComeFromTheLayerAssignmentOrTheClass) {
  auto layerObjects = [](const test::CollectingSink& sink) {
    std::map<std::string, int> counts;
    for (const SceneObject& o : sink.objects) counts[sink.layers[o.info.layer].name]++;
    return counts;
  };
  // IfcPresentationLayerAssignment: TestModel's four walls on its wall layer.
  EXPECT_EQ(layerObjects(import(sample("TestModel_IFC4Add2.ifc")))["A-WALL-____-OTLN"], 4);
  EXPECT_EQ(layerObjects(import(sample("bcf-mep.ifc")))["Supply air"], 8);
  // None in the file: the IFC class.
  EXPECT_EQ(layerObjects(import(sample("cylinders.ifc")))["IFCBUILDINGELEMENTPROXY"], 4);
}

// A wall 4 m long, 0.2 m thick and 3 m high (an extruded rectangle, its placement at x = 10),
// whose body item is `body` (#30 is the extrusion), followed by `more` instances.
std::string wallIfc(const std::string& body, const std::string& more) {
  return R"(ISO-10303-21;
HEADER;
FILE_DESCRIPTION((''),'2;1');
FILE_NAME('wall.ifc','',(''),(''),'','','');
FILE_SCHEMA(('IFC4'));
ENDSEC;
DATA;
#1=IFCUNITASSIGNMENT((#2));
#2=IFCSIUNIT(*,.LENGTHUNIT.,$,.METRE.);
#3=IFCCARTESIANPOINT((0.,0.,0.));
#4=IFCAXIS2PLACEMENT3D(#3,$,$);
#5=IFCCARTESIANPOINT((0.,0.));
#6=IFCAXIS2PLACEMENT2D(#5,$);
#7=IFCDIRECTION((0.,0.,1.));
#10=IFCWALL('2k7AL9Q4vAfOld2Ju8s3DV',$,'Wall',$,$,#11,#13,$,$);
#11=IFCLOCALPLACEMENT($,#12);
#12=IFCAXIS2PLACEMENT3D(#14,$,$);
#14=IFCCARTESIANPOINT((10.,0.,0.));
#13=IFCPRODUCTDEFINITIONSHAPE($,$,(#20));
#20=IFCSHAPEREPRESENTATION($,'Body','SweptSolid',()" + body + R"());
#31=IFCRECTANGLEPROFILEDEF(.AREA.,$,#6,4.,0.2);
#30=IFCEXTRUDEDAREASOLID(#31,#4,#7,3.);
)" + more + R"(ENDSEC;
END-ISO-10303-21;
)";
}

test::CollectingSink importText(const std::string& text, std::vector<std::string>* warnings) {
  const fs::path path = test::scratchDir() / "wall.ifc";
  test::writeFile(path, text);
  return import(path, warnings);
}

// The enclosed volume of a closed mesh (divergence theorem), and whether it is closed: every
// directed edge matched once by its reverse.
double closedVolume(const TriangleMesh& m, bool& closed) {
  std::map<std::pair<uint32_t, uint32_t>, int> directed;
  double volume = 0.0;
  for (size_t i = 0; i + 2 < m.indices.size(); i += 3) {
    const glm::dvec3 a(m.positions[m.indices[i]]), b(m.positions[m.indices[i + 1]]),
        c(m.positions[m.indices[i + 2]]);
    volume += glm::dot(a, glm::cross(b, c)) / 6.0;
    for (int k = 0; k < 3; ++k) directed[{m.indices[i + k], m.indices[i + (k + 1) % 3]}]++;
  }
  closed = true;
  for (const auto& [edge, count] : directed)
    closed = closed && count == 1 && directed.count({edge.second, edge.first}) == 1;
  return volume;
}

// Whether the segment from `p` to `q` crosses a triangle of `m`.
bool segmentHits(const TriangleMesh& m, const glm::dvec3& p, const glm::dvec3& q) {
  const glm::dvec3 d = q - p;
  for (size_t i = 0; i + 2 < m.indices.size(); i += 3) {
    const glm::dvec3 a(m.positions[m.indices[i]]), b(m.positions[m.indices[i + 1]]),
        c(m.positions[m.indices[i + 2]]);
    const glm::dvec3 e1 = b - a, e2 = c - a, h = glm::cross(d, e2);
    const double det = glm::dot(e1, h);
    if (std::abs(det) < 1e-15) continue;
    const glm::dvec3 s = p - a;
    const double u = glm::dot(s, h) / det;
    const glm::dvec3 qv = glm::cross(s, e1);
    const double v = glm::dot(d, qv) / det, t = glm::dot(e2, qv) / det;
    if (u >= 0 && v >= 0 && u + v <= 1 && t >= 0 && t <= 1) return true;
  }
  return false;
}

// The one object of a cut wall: a closed mesh, in the wall's frame.
const TriangleMesh& cutWall(const test::CollectingSink& sink) {
  EXPECT_EQ(sink.objects.size(), 1u);
  const auto* mesh = std::get_if<TriangleMesh>(&sink.objects.at(0).geometry);
  EXPECT_NE(mesh, nullptr) << "a cut box is a mesh";
  static const TriangleMesh none;
  return mesh ? *mesh : none;
}

// A window's opening (1 m wide, 1 m high, deeper than the wall, 1 m above the floor) voids the
// wall: the mesh is closed, holds exactly the wall less the hole, and a line of sight through
// the opening's centre meets nothing; beside it the wall is still there.
TEST(IfcImport, AnOpeningIsCutFromItsWall) {
  const std::string opening = R"(#40=IFCOPENINGELEMENT('3vB2YO$MX4xv5uCqZZG05x',$,'Opening',$,$,#41,#43,$,$);
#41=IFCLOCALPLACEMENT(#11,#42);
#42=IFCAXIS2PLACEMENT3D(#44,$,$);
#44=IFCCARTESIANPOINT((0.5,0.,1.));
#43=IFCPRODUCTDEFINITIONSHAPE($,$,(#45));
#45=IFCSHAPEREPRESENTATION($,'Body','SweptSolid',(#46));
#47=IFCRECTANGLEPROFILEDEF(.AREA.,$,#6,1.,0.6);
#46=IFCEXTRUDEDAREASOLID(#47,#4,#7,1.);
#50=IFCRELVOIDSELEMENT('1Q3vXHfGb0$9nTF1VlJ$Ug',$,$,$,#10,#40);
)";
  std::vector<std::string> warnings;
  const test::CollectingSink sink = importText(wallIfc("#30", opening), &warnings);
  for (const std::string& w : warnings) ADD_FAILURE() << w;
  const TriangleMesh& wall = cutWall(sink);
  bool closed = false;
  EXPECT_NEAR(closedVolume(wall, closed), 4.0 * 0.2 * 3.0 - 1.0 * 0.2 * 1.0, 1e-4);
  EXPECT_TRUE(closed);
  EXPECT_NEAR(sink.objects[0].info.transform.origin.x, 10.0, 1e-12) << "still placed by the wall";
  EXPECT_FALSE(segmentHits(wall, {0.5, -1.0, 1.5}, {0.5, 1.0, 1.5})) << "through the window";
  EXPECT_TRUE(segmentHits(wall, {-1.0, -1.0, 1.5}, {-1.0, 1.0, 1.5})) << "beside it";
}

// Colours through materials: a wall whose body carries no style takes the colour of the first
// layer of its material layer set (IfcMaterialDefinitionRepresentation), a style on the body
// item wins over it, and a material without a representation leaves the default.
TEST(IfcImport, AProductWithoutAStyleTakesItsMaterialsColour) {
  const std::string material = R"(#60=IFCMATERIAL('Brick',$,$);
#61=IFCMATERIALLAYER(#60,0.2,$,$,$,$,$);
#62=IFCMATERIALLAYERSET((#61),'Wall 200',$);
#63=IFCMATERIALLAYERSETUSAGE(#62,.AXIS2.,.POSITIVE.,0.,$);
#64=IFCRELASSOCIATESMATERIAL('0vSG6yzOX4kRzX6Y5BkDVY',$,$,$,(#10),#63);
#65=IFCCOLOURRGB($,0.8,0.4,0.2);
#66=IFCSURFACESTYLERENDERING(#65,0.,$,$,$,$,$,$,.NOTDEFINED.);
#67=IFCSURFACESTYLE('Brick',.BOTH.,(#66));
#68=IFCSTYLEDITEM($,(#67),$);
#69=IFCSTYLEDREPRESENTATION($,'Style','Material',(#68));
#70=IFCMATERIALDEFINITIONREPRESENTATION($,$,(#69),#60);
)";
  const std::string own_style = R"(#80=IFCCOLOURRGB($,0.,0.,1.);
#81=IFCSURFACESTYLERENDERING(#80,0.,$,$,$,$,$,$,.NOTDEFINED.);
#82=IFCSURFACESTYLE('Blue',.BOTH.,(#81));
#83=IFCSTYLEDITEM(#30,(#82),$);
)";
  auto colourOf = [](const std::string& text) {
    const test::CollectingSink sink = importText(text, nullptr);
    EXPECT_EQ(sink.objects.size(), 1u);
    return sink.objects.empty() ? 0u : sink.objects[0].info.color_rgba;
  };
  EXPECT_EQ(colourOf(wallIfc("#30", material)), 0xFF3366CCu) << "the material's brick red";
  EXPECT_EQ(colourOf(wallIfc("#30", material + own_style)), 0xFFFF0000u) << "the item's blue";
  const std::string no_representation = material.substr(0, material.find("#65="));
  EXPECT_EQ(colourOf(wallIfc("#30", no_representation)), 0u) << "no colour known";
}

// On the samples, the products left without a colour (9, 0 and 24 of them from the items' styles
// alone): TestModel's walls and slabs are coloured through their materials; acad2010's columns,
// beams and member through their type's material (a mapped representation of a type whose
// material has a style). TestModel's two railings and three stair parts have neither in the file.
TEST(IfcImport, TheSamplesColourProductsThroughTheirMaterials) {
  auto uncoloured = [](const char* name) {
    std::set<std::string> keys;
    for (const SceneObject& o : import(sample(name)).objects)
      if (o.info.color_rgba == 0) keys.insert(o.info.db_key);
    return keys.size();
  };
  EXPECT_EQ(uncoloured("TestModel_IFC4Add2.ifc"), 5u);
  EXPECT_EQ(uncoloured("bcf-architectural.ifc"), 0u);
  EXPECT_EQ(uncoloured("acad2010_objects.ifc"), 0u);
}

// IfcBooleanClippingResult: the wall less a half-space above z = 2.5 (normal up, material on
// its side: AgreementFlag false), less the one below it (true), and less a half-space bounded
// by a polygon covering only the wall's left half.
TEST(IfcImport, HalfSpacesClipTheirFirstOperand) {
  const std::string plane = R"(#60=IFCCARTESIANPOINT((0.,0.,2.5));
#61=IFCAXIS2PLACEMENT3D(#60,#7,$);
#62=IFCPLANE(#61);
)";
  auto clipped = [&](const std::string& half_space) {
    std::vector<std::string> warnings;
    const test::CollectingSink sink =
        importText(wallIfc("#80", plane + half_space + "#80=IFCBOOLEANCLIPPINGRESULT(.DIFFERENCE.,#30,#70);\n"),
                   &warnings);
    for (const std::string& w : warnings) ADD_FAILURE() << w;
    bool closed = false;
    const double volume = closedVolume(cutWall(sink), closed);
    EXPECT_TRUE(closed);
    return volume;
  };
  EXPECT_NEAR(clipped("#70=IFCHALFSPACESOLID(#62,.F.);\n"), 4.0 * 0.2 * 2.5, 1e-4);
  EXPECT_NEAR(clipped("#70=IFCHALFSPACESOLID(#62,.T.);\n"), 4.0 * 0.2 * 0.5, 1e-4);
  EXPECT_NEAR(clipped(R"(#70=IFCPOLYGONALBOUNDEDHALFSPACE(#62,.F.,#4,#71);
#71=IFCPOLYLINE((#72,#73,#74,#75,#72));
#72=IFCCARTESIANPOINT((-3.,-1.));
#73=IFCCARTESIANPOINT((0.,-1.));
#74=IFCCARTESIANPOINT((0.,1.));
#75=IFCCARTESIANPOINT((-3.,1.));
)"),
              4.0 * 0.2 * 3.0 - 2.0 * 0.2 * 0.5, 1e-4);
}

// IfcBooleanResult INTERSECTION: what the wall has in common with the half-space above z = 2.5.
TEST(IfcImport, AnIntersectionKeepsWhatItsOperandsShare) {
  const std::string text = wallIfc("#80", R"(#60=IFCCARTESIANPOINT((0.,0.,2.5));
#61=IFCAXIS2PLACEMENT3D(#60,#7,$);
#62=IFCPLANE(#61);
#70=IFCHALFSPACESOLID(#62,.F.);
#80=IFCBOOLEANRESULT(.INTERSECTION.,#30,#70);
)");
  std::vector<std::string> warnings;
  const test::CollectingSink sink = importText(text, &warnings);
  for (const std::string& w : warnings) ADD_FAILURE() << w;
  bool closed = false;
  EXPECT_NEAR(closedVolume(cutWall(sink), closed), 4.0 * 0.2 * 0.5, 1e-4);
  EXPECT_TRUE(closed);
}

// A cut that cannot be made (the opening's body is an open surface) keeps the wall whole and
// says so, naming the wall's #id.
TEST(IfcImport, ACutThatFailsKeepsTheHostAndNamesIt) {
  const std::string opening = R"(#40=IFCOPENINGELEMENT('3vB2YO$MX4xv5uCqZZG05x',$,'Opening',$,$,#41,#43,$,$);
#41=IFCLOCALPLACEMENT(#11,#4);
#43=IFCPRODUCTDEFINITIONSHAPE($,$,(#45));
#45=IFCSHAPEREPRESENTATION($,'Body','Tessellation',(#46));
#46=IFCTRIANGULATEDFACESET(#47,$,.F.,((1,2,3)),$);
#47=IFCCARTESIANPOINTLIST3D(((0.,-1.,1.),(1.,-1.,1.),(0.,1.,2.)));
#50=IFCRELVOIDSELEMENT('1Q3vXHfGb0$9nTF1VlJ$Ug',$,$,$,#10,#40);
)";
  std::vector<std::string> warnings;
  const test::CollectingSink sink = importText(wallIfc("#30", opening), &warnings);
  ASSERT_EQ(sink.objects.size(), 1u);
  EXPECT_TRUE(std::holds_alternative<Primitive>(sink.objects[0].geometry)) << "the box, uncut";
  bool named = false;
  for (const std::string& w : warnings)
    named |= w.find("#10 (in an IFCWALL): 1 opening (IfcRelVoidsElement) not cut: a mesh that") !=
             std::string::npos;
  EXPECT_TRUE(named) << (warnings.empty() ? "no warning" : warnings[0]);
}

// On the samples every opening and every clipping is cut (26 openings, 8 polygonal half-spaces),
// and the faces with holes of TestModel's walls keep their holes, so their shells close.
TEST(IfcImport, TheSamplesCutEveryOpeningAndClipping) {
  for (const char* file : {"TestModel_IFC4Add2.ifc", "acad2010_objects.ifc", "bcf-architectural.ifc"}) {
    std::vector<std::string> warnings;
    import(sample(file), &warnings);
    for (const std::string& w : warnings)
      EXPECT_EQ(w.find("not cut"), std::string::npos) << file << ": " << w;
  }
}

TEST(IfcImport, WhatIsNotReadIsAWarningNamingIt) {
  std::vector<std::string> warnings;
  importText(wallIfc("#30,#90", "#90=IFCADVANCEDBREP(#91);\n"), &warnings);
  bool named = false;
  for (const std::string& w : warnings) {
    EXPECT_NE(w.find("wall.ifc: "), std::string::npos) << w;
    named |= w.find("#90 (in an IFCWALL): geometry IFCADVANCEDBREP is not read; skipped") != std::string::npos;
  }
  EXPECT_TRUE(named);
}

TEST(IfcImport, Part21ErrorsNameTheLine) {
  auto rejects = [](const std::string& text, uint64_t line, const char* reason) {
    try {
      Step21File::parse(text, "t.ifc");
      ADD_FAILURE() << reason << ": accepted";
    } catch (const FormatError& e) {
      EXPECT_EQ(e.file(), "t.ifc");
      EXPECT_EQ(e.position(), line) << e.what();
      EXPECT_NE(e.reason().find(reason), std::string::npos) << e.what();
    }
  };
  const std::string head = "ISO-10303-21;\nHEADER;\nFILE_SCHEMA(('IFC4'));\nENDSEC;\nDATA;\n";
  const Step21File ok = Step21File::parse(
      head + "#1=IFCLABEL2('it''s \\X2\\00E9\\X0\\',(1,2.5E1,-3.),.T.,$,*,#2,IFCLABEL('x'));\n" +
          "#2=(A(1)B(2));\nENDSEC;\nEND-ISO-10303-21;\n",
      "t.ifc");
  EXPECT_EQ(ok.schema(), "IFC4");
  const Step21Instance* one = ok.find(1);
  ASSERT_NE(one, nullptr);
  ASSERT_EQ(one->args.size(), 7u);
  EXPECT_EQ(one->args[0].text, "it's \xc3\xa9");
  EXPECT_DOUBLE_EQ(one->args[1].items[1].number, 25.0);
  EXPECT_EQ(one->args[2].text, "T");
  EXPECT_TRUE(one->args[3].isNull());
  EXPECT_EQ(ok.deref(one->args[5]), ok.find(2));
  EXPECT_EQ(one->args[6].text, "IFCLABEL");
  EXPECT_EQ(ok.find(2)->type, "A");
  rejects("hello", 1, "does not start with ISO-10303-21");
  rejects(head + "#1=IFCWALL('abc);\n", 6, "unterminated string");
  rejects(head + "#1=IFCWALL((1,2);\n", 6, "expected ',' or ')'");
  rejects(head + "#1=IFCWALL(1);\n#1=IFCWALL(2);\n", 7, "defined twice");
  rejects(head + "#1=IFCWALL(1);\n", 7, "ends inside the DATA section");
  rejects(head + "#1=IFCWALL(" + std::string(100, '(') + ");\n", 6, "nested too deep");
}

TEST(IfcImport, TruncatedAndCorruptedFilesGiveAFormatErrorOrAScene) {
  const std::string original = test::readFile(sample("basic_shape_SweptSolid.ifc"));
  const int rejected = test::expectRobustToDamage(
      original, "damaged.ifc",
      [](const fs::path& p, SceneSink& sink) {
        ReadOptions quiet;
        quiet.warn = [](const std::string&) {};
        readIfc(p, sink, quiet);
      },
      300);
  EXPECT_GT(rejected, 250) << "every truncation loses END-ISO-10303-21";
}

// The same on a real building model (200 KB): references, lists and numbers damaged anywhere.
TEST(IfcImport, DamagedBuildingModelGivesAFormatErrorOrAScene) {
  const std::string original = test::readFile(sample("TestModel_IFC4Add2.ifc"));
  test::expectRobustToDamage(
      original, "damaged_building.ifc",
      [](const fs::path& p, SceneSink& sink) {
        ReadOptions quiet;
        quiet.warn = [](const std::string&) {};
        readIfc(p, sink, quiet);
      },
      200);
}

double triangleArea(const std::vector<glm::dvec2>& p, const std::vector<uint32_t>& t) {
  double area = 0.0;
  for (size_t i = 0; i < t.size(); i += 3) {
    const glm::dvec2 a = p[t[i]], b = p[t[i + 1]], c = p[t[i + 2]];
    area += 0.5 * ((b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x));
  }
  return area;
}

// A 4 x 3 plate with a 1 x 1 hole and a triangular one: the caps cover exactly the plate less
// the holes, every triangle counter-clockwise; the prism is closed (each edge used twice, once
// each way) whatever way the loops were wound.
TEST(ProfilePrism, HolesAreCutAndThePrismIsClosed) {
  std::vector<glm::dvec2> outer{{0, 0}, {4, 0}, {4, 3}, {0, 3}};
  std::vector<std::vector<glm::dvec2>> holes{{{1, 1}, {2, 1}, {2, 2}, {1, 2}},
                                             {{3, 0.5}, {3.5, 0.5}, {3.25, 2.5}}};
  for (int winding = 0; winding < 2; ++winding) {
    if (winding == 1) {
      std::reverse(outer.begin(), outer.end());
      for (auto& h : holes) std::reverse(h.begin(), h.end());
    }
    std::vector<glm::dvec2> all(outer);
    for (const auto& h : holes) all.insert(all.end(), h.begin(), h.end());
    const std::vector<uint32_t> cap = triangulateProfile(outer, holes);
    EXPECT_NEAR(triangleArea(all, cap), 12.0 - 1.0 - 0.5 * 0.5 * 2.0, 1e-9) << winding;
    for (size_t i = 0; i < cap.size(); i += 3)
      EXPECT_GT(triangleArea(all, {cap[i], cap[i + 1], cap[i + 2]}), 0.0);

    TriangleMesh prism;
    ASSERT_GT(appendProfilePrism(outer, holes, glm::dvec3(0.5, 0, 2), prism), 0u);
    std::map<std::pair<uint32_t, uint32_t>, int> directed;
    for (size_t i = 0; i < prism.indices.size(); i += 3)
      for (int k = 0; k < 3; ++k) directed[{prism.indices[i + k], prism.indices[i + (k + 1) % 3]}]++;
    for (const auto& [edge, count] : directed) {
      EXPECT_EQ(count, 1) << edge.first << "-" << edge.second;
      EXPECT_EQ(directed.count({edge.second, edge.first}), 1u) << edge.first << "-" << edge.second;
    }
  }
}

// Each steel section: counter-clockwise, centred on its bounding box, of the area its
// dimensions give, and as wide and deep as they say.
TEST(SteelProfiles, OutlinesHaveTheAreaAndBoxOfTheirDimensions) {
  struct Case {
    SteelSection section;
    std::vector<double> dimensions;
    double area, width, depth;
  };
  const std::vector<Case> cases = {
      {SteelSection::I, {0.2, 0.4, 0.01, 0.02}, 2 * 0.2 * 0.02 + 0.36 * 0.01, 0.2, 0.4},
      {SteelSection::L, {0.1, 0.08, 0.01}, 0.1 * 0.01 + 0.07 * 0.01, 0.08, 0.1},
      {SteelSection::L, {0.1, std::nan(""), 0.01}, 0.1 * 0.01 + 0.09 * 0.01, 0.1, 0.1},
      {SteelSection::T, {0.3, 0.2, 0.01, 0.02}, 0.2 * 0.02 + 0.28 * 0.01, 0.2, 0.3},
      {SteelSection::U, {0.3, 0.1, 0.01, 0.02}, 2 * 0.1 * 0.02 + 0.26 * 0.01, 0.1, 0.3},
      {SteelSection::C, {0.2, 0.08, 0.002, 0.02}, 0.2 * 0.002 + 2 * 0.078 * 0.002 + 2 * 0.018 * 0.002, 0.08, 0.2},
      {SteelSection::Z, {0.3, 0.1, 0.01, 0.02}, 2 * 0.1 * 0.02 + 0.26 * 0.01, 0.19, 0.3},
  };
  for (const Case& c : cases) {
    const std::vector<glm::dvec2> outline = steelSectionOutline(c.section, c.dimensions);
    EXPECT_NEAR(0.5 * loopArea2(outline), c.area, 1e-12) << int(c.section);
    glm::dvec2 lo(1e9), hi(-1e9);
    for (const glm::dvec2& p : outline) lo = glm::min(lo, p), hi = glm::max(hi, p);
    EXPECT_NEAR(hi.x - lo.x, c.width, 1e-12) << int(c.section);
    EXPECT_NEAR(hi.y - lo.y, c.depth, 1e-12) << int(c.section);
    EXPECT_NEAR(lo.x + hi.x, 0.0, 1e-12) << int(c.section);
    EXPECT_NEAR(lo.y + hi.y, 0.0, 1e-12) << int(c.section);
  }
  EXPECT_THROW(steelSectionOutline(SteelSection::I, {0.2, 0.4, 0.3, 0.02}), SteelSectionError);
  EXPECT_THROW(steelSectionOutline(SteelSection::U, {0.3, 0.1}), SteelSectionError);
  EXPECT_EQ(steelSectionOf("IFCZSHAPEPROFILEDEF"), SteelSection::Z);
  EXPECT_FALSE(steelSectionOf("IFCRECTANGLEPROFILEDEF"));
}

// A beam extruded from an IfcIShapeProfileDef stays parametric: an extrusion of the I.
TEST(IfcImport, SteelSectionsAreExtrusionsOfTheirOutline) {
  std::vector<std::string> warnings;
  const test::CollectingSink sink = importText(
      wallIfc("#95", "#96=IFCISHAPEPROFILEDEF(.AREA.,'IPE400',#6,0.18,0.4,0.0086,0.0135,0.021,$,$);\n"
                     "#95=IFCEXTRUDEDAREASOLID(#96,#4,#7,6.);\n"),
      &warnings);
  for (const std::string& w : warnings)
    EXPECT_EQ(w.find("skipped"), std::string::npos) << w;
  ASSERT_EQ(sink.objects.size(), 1u);
  const auto* e = std::get_if<Extrusion>(&std::get<Primitive>(sink.objects[0].geometry));
  ASSERT_NE(e, nullptr);
  EXPECT_EQ(e->profile.size(), 12u);
  EXPECT_FLOAT_EQ(e->height, 6.0f);
  std::vector<glm::dvec2> outline(e->profile.begin(), e->profile.end());
  EXPECT_NEAR(0.5 * loopArea2(outline), 2 * 0.18 * 0.0135 + (0.4 - 2 * 0.0135) * 0.0086, 1e-6);
}

// An IfcIndexedPolyCurve with an arc segment: the half-disc profile is sampled every 10 degrees
// (18 chords of the unit circle's upper half) and closed by its line segment.
TEST(IfcImport, ArcSegmentsOfIndexedPolyCurvesAreSampled) {
  std::vector<std::string> warnings;
  const test::CollectingSink sink = importText(
      wallIfc("#95", "#97=IFCCARTESIANPOINTLIST2D(((-1.,0.),(0.,1.),(1.,0.)));\n"
                     "#98=IFCINDEXEDPOLYCURVE(#97,(IFCARCINDEX((1,2,3)),IFCLINEINDEX((3,1))),.F.);\n"
                     "#96=IFCARBITRARYCLOSEDPROFILEDEF(.AREA.,$,#98);\n"
                     "#95=IFCEXTRUDEDAREASOLID(#96,#4,#7,2.);\n"),
      &warnings);
  for (const std::string& w : warnings) EXPECT_EQ(w.find("skipped"), std::string::npos) << w;
  ASSERT_EQ(sink.objects.size(), 1u);
  const auto* e = std::get_if<Extrusion>(&std::get<Primitive>(sink.objects[0].geometry));
  ASSERT_NE(e, nullptr);
  EXPECT_EQ(e->profile.size(), 19u);
  std::vector<glm::dvec2> outline(e->profile.begin(), e->profile.end());
  EXPECT_NEAR(0.5 * loopArea2(outline), 0.5 * 18 * std::sin(std::numbers::pi / 18.0), 1e-6);
  for (const glm::vec2& p : e->profile) EXPECT_GE(p.y, -1e-6f) << "the upper half, through (0, 1)";
}

// A placement chain that loops is followed to a bounded depth, not forever.
TEST(IfcImport, PlacementLoopDoesNotHang) {
  std::string text = test::readFile(sample("basic_shape_SweptSolid.ifc"));
  // Make the product's placement relative to itself.
  const size_t at = text.find("IFCLOCALPLACEMENT(");
  ASSERT_NE(at, std::string::npos);
  const size_t hash = text.rfind('#', at);
  const std::string id = text.substr(hash, text.find('=', hash) - hash);
  const size_t open = at + std::string("IFCLOCALPLACEMENT(").size();
  const size_t comma = text.find(',', open);
  text.replace(open, comma - open, id);
  const fs::path path = test::scratchDir() / "loop.ifc";
  test::writeFile(path, text);
  const test::CollectingSink sink = import(path);
  EXPECT_EQ(sink.objects.size(), 1u);
}

}  // namespace
}  // namespace tw

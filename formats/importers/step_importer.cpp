// STEP import through OpenCASCADE XDE. See step_importer.h.
#include "step_importer.h"

#include <BRepBndLib.hxx>
#include <BRepMesh_IncrementalMesh.hxx>
#include <BRep_Tool.hxx>
#include <Bnd_Box.hxx>
#include <GeomAdaptor_Surface.hxx>
#include <IFSelect_ReturnStatus.hxx>
#include <Interface_Check.hxx>
#include <Interface_CheckIterator.hxx>
#include <Interface_InterfaceModel.hxx>
#include <Interface_Static.hxx>
#include <Message.hxx>
#include <Message_Messenger.hxx>
#include <Message_Printer.hxx>
#include <Poly_Triangulation.hxx>
#include <Quantity_Color.hxx>
#include <STEPCAFControl_Reader.hxx>
#include <StepData_StepModel.hxx>
#include <XSControl_WorkSession.hxx>
#include <Standard_Failure.hxx>
#include <TColStd_HSequenceOfExtendedString.hxx>
#include <TDF_Label.hxx>
#include <TDF_LabelSequence.hxx>
#include <TDataStd_Name.hxx>
#include <TDocStd_Document.hxx>
#include <TopExp_Explorer.hxx>
#include <TopLoc_Location.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Face.hxx>
#include <XCAFApp_Application.hxx>
#include <XCAFDoc_ColorTool.hxx>
#include <XCAFDoc_DocumentTool.hxx>
#include <XCAFDoc_LayerTool.hxx>
#include <XCAFDoc_ShapeTool.hxx>
#include <gp_Trsf.hxx>

#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <csignal>
#include <atomic>
#include <cerrno>
#include <cstring>
#include <cmath>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <unordered_map>
#include <vector>

#include "face_weld.h"
#include "format_error.h"
#include "step_bspline_faces.h"
#include "step_face_mesher.h"
#include "step_primitives.h"
#include "tws_reader.h"
#include "tws_writer.h"

namespace tw {
namespace {

// The chordal tolerance of the meshing: the scene's default (2 mm), tightened for small parts
// so a 10 mm nut is not a hexagon of facets.
constexpr double kMaxDeflectionM = 0.002;
constexpr double kRelativeDeflection = 0.002;  // of the part's bounding diagonal
constexpr double kAngularDeflectionRad = 0.35;  // 20 degrees

// OpenCASCADE reports through its default messenger, which prints to stdout. While a file is
// read the printers are swapped for one that keeps the failures, so the error names what
// OpenCASCADE said, and the command line prints nothing of its own.
class FailureCollector : public Message_Printer {
 public:
  const std::vector<std::string>& failures() const { return failures_; }

 protected:
  void send(const TCollection_AsciiString& text, const Message_Gravity gravity) const override {
    if (gravity >= Message_Fail && failures_.size() < 8) failures_.emplace_back(text.ToCString());
  }

 private:
  mutable std::vector<std::string> failures_;
};

class QuietMessenger {
 public:
  QuietMessenger() : collector_(new FailureCollector) {
    const Handle(Message_Messenger)& messenger = Message::DefaultMessenger();
    saved_ = messenger->Printers();
    messenger->ChangePrinters().Clear();
    messenger->AddPrinter(collector_);
  }
  ~QuietMessenger() {
    const Handle(Message_Messenger)& messenger = Message::DefaultMessenger();
    messenger->ChangePrinters() = saved_;
  }
  QuietMessenger(const QuietMessenger&) = delete;
  QuietMessenger& operator=(const QuietMessenger&) = delete;

  // "; OpenCASCADE: first failure" when it reported one.
  std::string said() const {
    const auto& f = collector_->failures();
    if (f.empty()) return "";
    std::string first = f.front();
    std::replace(first.begin(), first.end(), '\n', ' ');
    return "; OpenCASCADE: " + first;
  }

 private:
  Handle(FailureCollector) collector_;
  Message_SequenceOfPrinters saved_;
};

std::string labelName(const TDF_Label& label) {
  Handle(TDataStd_Name) name;
  if (!label.FindAttribute(TDataStd_Name::GetID(), name)) return "";
  return TCollection_AsciiString(name->Get()).ToCString();
}

uint32_t rgba(const Quantity_Color& c) {
  auto channel = [](double v) { return uint32_t(std::lround(std::clamp(v, 0.0, 1.0) * 255.0)); };
  double r, g, b;
  c.Values(r, g, b, Quantity_TOC_sRGB);
  return channel(r) | (channel(g) << 8) | (channel(b) << 16) | 0xff000000u;
}

// A product's faces, meshed and welded by the shared edge discretizations, in metres relative to
// `center` (the part's box centre, so floats keep their precision far from the datum).
struct PartMesh {
  glm::dvec3 center{0.0};
  TriangleMesh mesh;
  std::optional<RecognizedPrimitive> primitive;  // instead of the mesh, when the part is one
  uint32_t bspline_faces = 0;     // B-spline and Bezier faces
  uint32_t conforming_faces = 0;  // of those, untrimmed: zipped to the B-rep's edge nodes
  uint32_t planned_faces = 0;     // trimmed: on the tessellator's grid clipped to their wires
};

// Positions are compared within this share of the part's size when recognizing primitives.
constexpr double kRelativePrimitiveTolerance = 1e-6;

std::optional<RecognizedPrimitive> primitiveOfPart(const TopoDS_Shape& shape) {
  Bnd_Box box;
  BRepBndLib::Add(shape, box);
  if (box.IsVoid()) return std::nullopt;
  const double diagonal = std::sqrt(box.SquareExtent());
  return recognizePrimitive(shape, std::max(1e-12, kRelativePrimitiveTolerance * diagonal));
}

PartMesh meshPart(const TopoDS_Shape& shape, double fixed_deflection, bool conforming_bspline) {
  PartMesh part;
  Bnd_Box box;
  BRepBndLib::Add(shape, box);
  if (box.IsVoid()) return part;
  double x0, y0, z0, x1, y1, z1;
  box.Get(x0, y0, z0, x1, y1, z1);
  part.center = glm::dvec3(0.5 * (x0 + x1), 0.5 * (y0 + y1), 0.5 * (z0 + z1));
  const double diagonal = std::sqrt((x1 - x0) * (x1 - x0) + (y1 - y0) * (y1 - y0) +
                                    (z1 - z0) * (z1 - z0));
  const double deflection =
      fixed_deflection > 0.0 ? fixed_deflection
                             : std::max(1e-6, std::min(kMaxDeflectionM, kRelativeDeflection * diagonal));
  TopTools_MapOfShape planned_faces;
  if (conforming_bspline)
    meshShapeFaces(shape, deflection, kAngularDeflectionRad, planned_faces);
  else
    BRepMesh_IncrementalMesh opencascade_only(shape, deflection, false, kAngularDeflectionRad, false);

  // Nodes shared along edges are exact copies, so a weld by exact position joins the faces.
  FaceWeld weld(part.mesh, part.center);
  for (TopExp_Explorer e(shape, TopAbs_FACE); e.More(); e.Next()) {
    const TopoDS_Face& face = TopoDS::Face(e.Current());
    TopLoc_Location location;
    const Handle(Poly_Triangulation) triangulation = BRep_Tool::Triangulation(face, location);
    if (triangulation.IsNull()) continue;
    const gp_Trsf placement = location.Transformation();
    const std::vector<uint32_t>& node_index = weld.addNodes(*triangulation, placement);
    const GeomAbs_SurfaceType kind = GeomAdaptor_Surface(BRep_Tool::Surface(face)).GetType();
    if (kind == GeomAbs_BSplineSurface || kind == GeomAbs_BezierSurface) {
      ++part.bspline_faces;
      if (conforming_bspline &&
          tessellateBSplineFace(face, *triangulation, placement, part.center, node_index,
                                deflection, part.mesh)) {
        ++part.conforming_faces;
        continue;
      }
      if (planned_faces.Contains(face)) ++part.planned_faces;
    }
    weld.addTriangles(*triangulation, face.Orientation() == TopAbs_REVERSED);
  }
  return part;
}

// `local` (a primitive's frame in the part's coordinates) carried by `placement`.
Transform composed(const gp_Trsf& placement, const Transform& local) {
  Transform t;
  const gp_Pnt origin = gp_Pnt(local.origin.x, local.origin.y, local.origin.z).Transformed(placement);
  t.origin = glm::dvec3(origin.X(), origin.Y(), origin.Z());
  glm::dmat3 linear;
  for (int column = 0; column < 3; ++column)
    for (int row = 0; row < 3; ++row) linear[column][row] = placement.Value(row + 1, column + 1);
  t.linear = glm::mat3(linear * glm::dmat3(local.linear));
  return t;
}

// Hands `mesh` to the sink in parts of at most max_triangles triangles, each part holding only
// the vertices it uses.
void emitInParts(SceneSink& sink, const ObjectInfo& info, const TriangleMesh& mesh,
                 uint32_t max_triangles) {
  const uint64_t triangles = mesh.triangleCount();
  if (triangles <= max_triangles) {
    sink.onObject(SceneObject{info, mesh});
    return;
  }
  std::vector<uint32_t> remap(mesh.positions.size(), UINT32_MAX);
  for (uint64_t first = 0; first < triangles; first += max_triangles) {
    const uint64_t last = std::min<uint64_t>(triangles, first + max_triangles);
    TriangleMesh part;
    std::vector<uint32_t> used;
    for (uint64_t i = first * 3; i < last * 3; ++i) {
      const uint32_t v = mesh.indices[i];
      if (remap[v] == UINT32_MAX) {
        remap[v] = uint32_t(part.positions.size());
        part.positions.push_back(mesh.positions[v]);
        used.push_back(v);
      }
      part.indices.push_back(remap[v]);
    }
    for (uint32_t v : used) remap[v] = UINT32_MAX;
    sink.onObject(SceneObject{info, std::move(part)});
  }
}

// Walks the XDE assembly tree and emits one object per part instance.
class AssemblyWalker {
 public:
  AssemblyWalker(const Handle(TDocStd_Document)& doc, SceneSink& sink, const ReadOptions& options)
      : shapes_(XCAFDoc_DocumentTool::ShapeTool(doc->Main())),
        colors_(XCAFDoc_DocumentTool::ColorTool(doc->Main())),
        layers_(XCAFDoc_DocumentTool::LayerTool(doc->Main())),
        sink_(sink),
        max_part_triangles_(std::max<uint32_t>(1, options.max_part_triangles)),
        keep_primitives_(options.cad.primitives),
        deflection_m_(options.cad.tolerance_m),
        conforming_bspline_(options.cad.conforming_bspline) {
    TDF_LabelSequence layer_labels;
    layers_->GetLayerLabels(layer_labels);
    file_has_layers_ = layer_labels.Length() > 0;
  }

  void walkRoots() {
    TDF_LabelSequence roots;
    shapes_->GetFreeShapes(roots);
    std::map<std::string, int> seen;
    for (int i = 1; i <= roots.Length(); ++i) {
      const std::string name = uniqueName(nodeName(roots(i), roots(i)), seen);
      walk(roots(i), gp_Trsf(), name, /*depth=*/0, /*top_layer=*/"");
    }
  }

  uint32_t objects() const { return next_id_; }

  // Over the distinct products: B-spline and Bezier faces, and those tessellated conforming.
  void faceCounts(uint64_t& bspline, uint64_t& conforming, uint64_t& planned) const {
    bspline = conforming = planned = 0;
    for (const auto& [shape, part] : meshes_) {
      bspline += part.bspline_faces;
      conforming += part.conforming_faces;
      planned += part.planned_faces;
    }
  }

 private:
  std::string nodeName(const TDF_Label& instance, const TDF_Label& product) const {
    std::string name = labelName(instance);
    if (name.empty() || name.rfind("=>", 0) == 0) name = labelName(product);
    if (name.empty() || name.rfind("=>", 0) == 0) name = "part";
    std::replace(name.begin(), name.end(), '/', '_');
    return name;
  }

  static std::string uniqueName(const std::string& name, std::map<std::string, int>& seen) {
    const int n = ++seen[name];
    return n == 1 ? name : name + ":" + std::to_string(n);
  }

  uint32_t layerIndex(const std::string& name) {
    auto [it, inserted] = layer_index_.emplace(name, uint32_t(layer_index_.size()));
    if (inserted) sink_.onLayer(it->second, Layer{name});
    return it->second;
  }

  std::string fileLayer(const TDF_Label& instance, const TDF_Label& product) const {
    for (const TDF_Label& label : {instance, product}) {
      Handle(TColStd_HSequenceOfExtendedString) names;
      if (layers_->GetLayers(label, names) && !names.IsNull() && names->Length() > 0)
        return TCollection_AsciiString(names->Value(1)).ToCString();
    }
    return "";
  }

  bool colorOf(const TDF_Label& instance, const TDF_Label& product, uint32_t& out) const {
    Quantity_Color c;
    for (const TDF_Label& label : {instance, product})
      for (XCAFDoc_ColorType type : {XCAFDoc_ColorSurf, XCAFDoc_ColorGen})
        if (colors_->GetColor(label, type, c)) {
          out = rgba(c);
          return true;
        }
    return false;
  }

  void walk(const TDF_Label& node, const gp_Trsf& parent, const std::string& path, int depth,
            const std::string& top_layer) {
    TDF_Label product = node;
    gp_Trsf placement = parent;
    if (shapes_->IsReference(node)) {
      shapes_->GetReferredShape(node, product);
      placement = parent * shapes_->GetLocation(node).Transformation();
    }
    // Without file layers, the root's top-level components name the layers (a lone part is its
    // own layer).
    const std::string layer_here = depth == 1 || top_layer.empty() ? path.substr(path.rfind('/') + 1)
                                                                   : top_layer;
    if (shapes_->IsAssembly(product)) {
      TDF_LabelSequence components;
      shapes_->GetComponents(product, components);
      std::map<std::string, int> seen;
      for (int i = 1; i <= components.Length(); ++i) {
        TDF_Label child_product = components(i);
        shapes_->GetReferredShape(components(i), child_product);
        const std::string child = uniqueName(nodeName(components(i), child_product), seen);
        walk(components(i), placement, path + "/" + child, depth + 1,
             depth == 0 ? "" : layer_here);
      }
      return;
    }
    emitPart(node, product, placement, path, layer_here);
  }

  void emitPart(const TDF_Label& instance, const TDF_Label& product, const gp_Trsf& placement,
                const std::string& path, const std::string& fallback_layer) {
    const TopoDS_Shape shape = shapes_->GetShape(product);
    if (shape.IsNull()) return;
    auto cached = meshes_.find(shape.TShape().get());
    if (cached == meshes_.end()) {
      const TopoDS_Shape unplaced = shape.Located(TopLoc_Location());
      PartMesh part;
      if (keep_primitives_) part.primitive = primitiveOfPart(unplaced);
      if (!part.primitive) part = meshPart(unplaced, deflection_m_, conforming_bspline_);
      cached = meshes_.emplace(shape.TShape().get(), std::move(part)).first;
    }
    const PartMesh& part = cached->second;
    if (!part.primitive && part.mesh.indices.empty()) return;  // curves, points, empty compounds

    ObjectInfo info;
    info.id = next_id_++;
    info.name = path;
    info.db_key = path;
    const std::string file_layer = file_has_layers_ ? fileLayer(instance, product) : "";
    info.layer = layerIndex(!file_layer.empty() ? file_layer
                            : file_has_layers_ ? std::string("default")
                                               : fallback_layer);
    colorOf(instance, product, info.color_rgba);
    // The product's own location (a shape label may carry one) comes before the instance's.
    const gp_Trsf own = shape.Location().Transformation();
    if (part.primitive) {
      info.transform = composed(placement * own, part.primitive->frame);
      sink_.onObject(SceneObject{info, part.primitive->primitive});
      return;
    }
    Transform centred;  // the mesh's positions are relative to the part's box centre
    centred.origin = part.center;
    info.transform = composed(placement * own, centred);
    emitInParts(sink_, info, part.mesh, max_part_triangles_);
  }

  Handle(XCAFDoc_ShapeTool) shapes_;
  Handle(XCAFDoc_ColorTool) colors_;
  Handle(XCAFDoc_LayerTool) layers_;
  SceneSink& sink_;
  uint32_t max_part_triangles_;
  bool keep_primitives_;
  double deflection_m_;  // 0: the per-part rule
  bool conforming_bspline_;
  bool file_has_layers_ = false;
  uint32_t next_id_ = 0;
  std::map<std::string, uint32_t> layer_index_;
  std::unordered_map<const void*, PartMesh> meshes_;  // by TopoDS_TShape: one mesh per product
};

// OpenCASCADE's translation trusts the model: text that failed to parse leaves null handles it
// dereferences. So the model's checks come first: a failure of the file as a whole (a syntax
// error) is an error naming OpenCASCADE's reason; a failure of one entity (a parameter of the
// wrong type, often in presentation data) is a warning naming the entity, and the rest is read.
constexpr int kMaxEntityWarnings = 10;

void checkModel(const STEPCAFControl_Reader& reader, const std::string& file,
                const ReadOptions& options) {
  const Handle(XSControl_WorkSession) session = reader.Reader().WS();
  const Handle(Interface_InterfaceModel) model = reader.Reader().Model();
  if (session.IsNull() || model.IsNull()) throw FormatError(file, "STEP model did not load");
  const Handle(StepData_StepModel) step = Handle(StepData_StepModel)::DownCast(model);
  const Interface_CheckIterator checks = session->ModelCheckList();
  int entity_failures = 0;
  for (checks.Start(); checks.More(); checks.Next()) {
    const Handle(Interface_Check)& check = checks.Value();
    if (check.IsNull() || !check->HasFailed()) continue;
    std::string reason = check->CFail(1);
    std::replace(reason.begin(), reason.end(), '\n', ' ');
    const int number = checks.Number();
    if (number <= 0 || number > model->NbEntities())
      throw FormatError(file, "not a valid STEP file: " + reason);
    if (++entity_failures > kMaxEntityWarnings) continue;
    const int label = step.IsNull() ? 0 : step->IdentLabel(model->Value(number));
    const std::string where = label > 0 ? "entity #" + std::to_string(label)
                                        : "entity " + std::to_string(number) + " of the model";
    readWarning(options, file + ": " + where + ": " + reason + " (read on)");
  }
  if (entity_failures > kMaxEntityWarnings)
    readWarning(options, file + ": " + std::to_string(entity_failures - kMaxEntityWarnings) +
                             " more entities failed their checks (read on)");
}

// The translation proper, in the child: STEP into a scene file, warnings and the error as lines
// on `report` ("W" or "E" and the text).
void translate(const std::filesystem::path& path, const std::filesystem::path& scene,
               const ReadOptions& options, int report) {
  auto send = [report](char kind, const std::string& text) {
    std::string line = kind + text;
    std::replace(line.begin(), line.end(), '\n', ' ');
    line += '\n';
    for (size_t done = 0; done < line.size();) {
      const ssize_t n = ::write(report, line.data() + done, line.size() - done);
      if (n <= 0) return;
      done += size_t(n);
    }
  };
  const std::string file = path.string();
  ReadOptions child = options;
  child.progress = nullptr;
  child.warn = [&](const std::string& message) { send('W', message); };
  QuietMessenger quiet;
  try {
    Handle(XCAFApp_Application) app = XCAFApp_Application::GetApplication();
    Handle(TDocStd_Document) doc;
    app->NewDocument("MDTV-XCAF", doc);
    STEPCAFControl_Reader reader;  // registers the STEP parameters set below
    // Lengths in metres, whatever the file's unit.
    if (!Interface_Static::SetCVal("xstep.cascade.unit", "M"))
      throw FormatError(file, "OpenCASCADE refused the metre as the target unit");
    reader.SetColorMode(true);
    reader.SetNameMode(true);
    reader.SetLayerMode(true);
    if (reader.ReadFile(file.c_str()) != IFSelect_RetDone)
      throw FormatError(file, "not a readable STEP file" + quiet.said());
    checkModel(reader, file, child);
    if (!reader.Transfer(doc))
      throw FormatError(file, "STEP model has nothing OpenCASCADE can transfer" + quiet.said());
    TwsWriter writer(scene);
    AssemblyWalker walker(doc, writer, child);
    walker.walkRoots();
    if (walker.objects() == 0)
      throw FormatError(file, "STEP model holds no faces to mesh" + quiet.said());
    writer.finish();
    uint64_t bspline = 0, conforming = 0, planned = 0;
    walker.faceCounts(bspline, conforming, planned);
    if (bspline > 0)
      send('N', "B-spline faces " + std::to_string(bspline) + " by the conforming tessellator: " +
                    std::to_string(conforming) + " untrimmed zipped to the B-rep's edge nodes, " +
                    std::to_string(planned) + " trimmed on its grid clipped to their wires (refined by BRepMesh's deflection "
                    "control); " +
                    std::to_string(bspline - conforming - planned) + " by BRepMesh alone");
  } catch (const FormatError& e) {
    send('E', e.reason());
  } catch (const Standard_Failure& failure) {
    send('E', std::string("OpenCASCADE failed: ") +
                  (failure.GetMessageString() ? failure.GetMessageString() : "") + quiet.said());
  } catch (const std::exception& e) {
    send('E', e.what());
  }
}

// A scene file in the temporary directory, removed when this goes out of scope.
class TemporaryScene {
 public:
  TemporaryScene() {
    static std::atomic<uint64_t> counter{0};
    path_ = std::filesystem::temp_directory_path() /
            ("terawalk-step-" + std::to_string(::getpid()) + "-" + std::to_string(counter++) +
             ".tws");
  }
  ~TemporaryScene() {
    std::error_code ec;
    std::filesystem::remove(path_, ec);
  }
  TemporaryScene(const TemporaryScene&) = delete;
  TemporaryScene& operator=(const TemporaryScene&) = delete;
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};

// One finished translation: the scene file the child wrote and the warnings it sent.
struct Translation {
  std::shared_ptr<const TemporaryScene> scene;
  std::vector<std::string> warnings;
  std::vector<std::string> notes;
};

// Runs the translation in a child process. OpenCASCADE dereferences what a damaged file leaves
// null, so a crash there must be an error here; its memory also goes back when it exits.
Translation translateInChild(const std::filesystem::path& path, const ReadOptions& options) {
  const std::string file = path.string();
  auto scene = std::make_shared<const TemporaryScene>();
  int fds[2];
  if (::pipe(fds) != 0) throw FormatError(file, "cannot create a pipe for the STEP translation");
  const pid_t child = ::fork();
  if (child < 0) {
    ::close(fds[0]);
    ::close(fds[1]);
    throw FormatError(file, "cannot start the STEP translation process");
  }
  if (child == 0) {
    ::close(fds[0]);
    // A crash inside OpenCASCADE is this child's expected way to fail: let it die of the signal,
    // which the parent turns into the error below, rather than run a handler a sanitizer or a
    // fuzzer installed in the parent (it would report the crash as its own and write files).
    std::signal(SIGSEGV, SIG_DFL);
    std::signal(SIGBUS, SIG_DFL);
    translate(path, scene->path(), options, fds[1]);
    ::close(fds[1]);
    ::_exit(0);
  }
  ::close(fds[1]);
  std::string report;
  char buffer[4096];
  for (ssize_t n; (n = ::read(fds[0], buffer, sizeof buffer)) != 0;) {
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) break;
    report.append(buffer, size_t(n));
  }
  ::close(fds[0]);
  int status = 0;
  while (::waitpid(child, &status, 0) < 0 && errno == EINTR) {
  }
  Translation done{scene, {}, {}};
  std::string error;
  for (size_t at = 0; at < report.size();) {
    const size_t end = std::min(report.find('\n', at), report.size());
    const std::string line = report.substr(at, end - at);
    at = end + 1;
    if (line.empty()) continue;
    if (line[0] == 'W') done.warnings.push_back(line.substr(1));
    else if (line[0] == 'N') done.notes.push_back(line.substr(1));
    else if (line[0] == 'E' && error.empty()) error = line.substr(1);
  }
  if (WIFSIGNALED(status))
    throw FormatError(file, std::string("OpenCASCADE crashed translating the file (") +
                                strsignal(WTERMSIG(status)) +
                                "): it is damaged or holds what OpenCASCADE cannot read");
  if (!error.empty()) throw FormatError(file, error);
  // The child exits 0 whatever it read (errors come over the pipe), so any other status is a
  // crash that a handler turned into an exit (a sanitizer's, for one).
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0)
    throw FormatError(file, "OpenCASCADE crashed translating the file (exit status " +
                                std::to_string(WIFEXITED(status) ? WEXITSTATUS(status) : -1) +
                                "): it is damaged or holds what OpenCASCADE cannot read");
  return done;
}

// The preprocessor reads each input twice (survey, then bricking): the second reading of an
// unchanged file with the same options reuses the first's scene file instead of translating
// again. A few files are kept, until the process exits.
class TranslationCache {
 public:
  static TranslationCache& instance() {
    static TranslationCache cache;
    return cache;
  }

  // The key: what the translation's output depends on.
  static std::string keyOf(const std::filesystem::path& path, const ReadOptions& options) {
    std::error_code ec;
    const auto canonical = std::filesystem::weakly_canonical(path, ec);
    const auto size = std::filesystem::file_size(path, ec);
    const auto time = std::filesystem::last_write_time(path, ec).time_since_epoch().count();
    return (ec ? path.string() : canonical.string()) + "|" + std::to_string(size) + "|" +
           std::to_string(time) + "|" + std::to_string(options.cad.primitives) + "|" +
           std::to_string(options.cad.tolerance_m) + "|" +
           std::to_string(options.cad.conforming_bspline) + "|" + std::to_string(options.max_part_triangles);
  }

  std::optional<Translation> find(const std::string& key) {
    std::lock_guard<std::mutex> lock(mutex_);
    for (const auto& [k, t] : entries_)
      if (k == key) return t;
    return std::nullopt;
  }

  void add(const std::string& key, const Translation& translation) {
    std::lock_guard<std::mutex> lock(mutex_);
    entries_.emplace_back(key, translation);
    if (entries_.size() > kEntries) entries_.erase(entries_.begin());
  }

 private:
  static constexpr size_t kEntries = 4;
  std::mutex mutex_;
  std::vector<std::pair<std::string, Translation>> entries_;
};

}  // namespace

void readStep(const std::filesystem::path& path, SceneSink& sink, const ReadOptions& options) {
  const std::string file = path.string();
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec))
    throw FormatError(file, "cannot open: no such file");
  const std::string key = TranslationCache::keyOf(path, options);
  std::optional<Translation> translation = TranslationCache::instance().find(key);
  if (!translation) {
    translation = translateInChild(path, options);
    TranslationCache::instance().add(key, *translation);
  }
  for (const std::string& warning : translation->warnings) readWarning(options, warning);
  if (options.note)
    for (const std::string& note : translation->notes) options.note(note);
  ReadOptions scene_options = options;
  scene_options.progress = nullptr;
  readTws(translation->scene->path(), sink, scene_options);
  if (options.progress) updateProgress(options.progress, std::filesystem::file_size(path, ec));
}

}  // namespace tw

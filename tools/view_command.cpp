// `terawalk view model.twk`: the interactive walkthrough in a GLFW window (works under xvfb-run).
//
// Game-like navigation (WASD + mouse look with the left button, Shift to run, Q/E down/up, the
// wheel scales the speed, which starts from the model's size), an orbit mode (O) around the
// model's centre, a screenshot key (F12), a camera-path recorder (R starts and stops; the path is
// written in the documented text format) and replay (--path). An ImGui overlay shows the frame
// statistics and sets tau, field of view, near/far, the small-feature threshold and the occlusion
// mode (off, hzb, pvs; --occlusion picks the first) and the parametrics mode (impostor,
// tessellated, off; --parametrics picks the first, auto by default, P cycles) at run time.
// A click selects the object under the cursor (Ctrl adds or removes, a double click frames the
// selection, Esc clears it) and the properties panel shows its record from the project database
// (view_selection.h); the review panel hides, isolates and X-rays layers, searches names, keys
// and the database, and saves selection sets next to the package (view_review.h); --script
// plays clicks, keys and the review's actions at given frames (view_script.h).
// The same Walkthrough as `terawalk render` draws every frame.
#include <GL/gl.h>
#include <GLFW/glfw3.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <optional>
#include <cstdio>
#include <stdexcept>
#include <string>

#include <imgui.h>
#include <imgui_impl_glfw.h>
#include <imgui_impl_opengl3.h>

#include "camera_path.h"
#include "command.h"
#include "command_args.h"
#include "environment_options.h"
#include "frame_loop.h"
#include "image_compare.h"
#include "object_pick.h"
#include "package_database.h"
#include "project_database.h"
#include "selection_sets.h"
#include "change_set.h"
#include "snapshot_camera.h"
#include "section_planes.h"
#include "view_edits.h"
#include "view_environment.h"
#include "view_path.h"
#include "stereo_options.h"
#include "view_stereo.h"
#include "view_log.h"
#include "view_measure.h"
#include "view_sections.h"
#include "view_viewpoints.h"
#include "review_archive.h"
#include "view_review.h"
#include "view_script.h"
#include "view_selection.h"

namespace tw {
namespace {

struct ViewArgs {
  std::string file;
  std::string size = "1280x720";
  std::string path_file;
  std::string record_file = "recorded.path";
  std::string gpu_budget = "1G";
  double tau_px = 1.0;
  double target_fps = 0.0;
  int frames = 0;  // > 0: quit after this many frames (scripted runs, tests)
  std::string screenshot;  // with --frames: write the last frame here
  std::string occlusion = "hzb";
  std::string parametrics = "auto";
  std::string db;      // the project database, for the properties panel
  std::string script;  // clicks and keys at given frames (view_script.h)
  EnvironmentArgs environment;  // --ocean, --sky and their settings
  StereoArgs stereo_args;  // --stereo and its distances
  StereoOptions stereo;    // what they say, checked by runView
};

struct GlfwSession {
  GlfwSession() {
    if (!glfwInit()) throw std::runtime_error("GLFW: cannot initialise (no display? try xvfb-run -a)");
  }
  ~GlfwSession() { glfwTerminate(); }
};

void saveScreenshot(GlRenderer& renderer, const std::string& file) {
  std::vector<uint8_t> rgba;
  renderer.readColor(rgba, true);
  writePngRgba(file, renderer.width(), renderer.height(), rgba);
  std::fprintf(stderr, "view: wrote %s\n", file.c_str());
}

// Camera motion from the keyboard and mouse, walk and orbit modes.
struct Navigator {
  double speed_mps = 10.0;
  bool orbit = false;
  glm::dvec3 orbit_target{0.0};
  double orbit_distance = 100.0;
  bool dragging = false;
  double last_x = 0.0, last_y = 0.0;

  // `mouse_taken`: the gizmo holds the mouse (a handle is being dragged).
  void update(GLFWwindow* window, Camera& camera, double dt, bool mouse_taken) {
    const bool ui_mouse = ImGui::GetIO().WantCaptureMouse || mouse_taken;
    const bool ui_keys = ImGui::GetIO().WantCaptureKeyboard;
    double x = 0.0, y = 0.0;
    glfwGetCursorPos(window, &x, &y);
    const bool down = glfwGetMouseButton(window, GLFW_MOUSE_BUTTON_LEFT) == GLFW_PRESS;
    if (down && !dragging && !ui_mouse) dragging = true;
    if (!down || mouse_taken) dragging = false;
    if (dragging) {
      const double k = 0.003;
      camera.yaw_rad -= (x - last_x) * k;
      camera.pitch_rad = std::clamp(camera.pitch_rad - (y - last_y) * k, -1.55, 1.55);
    }
    last_x = x;
    last_y = y;
    if (orbit) {
      camera.position = orbit_target - camera.forward() * orbit_distance;
      return;
    }
    if (ui_keys) return;
    auto key = [&](int k) { return glfwGetKey(window, k) == GLFW_PRESS; };
    double v = speed_mps * dt;
    if (key(GLFW_KEY_LEFT_SHIFT) || key(GLFW_KEY_RIGHT_SHIFT)) v *= 5.0;
    if (key(GLFW_KEY_W)) camera.position += camera.forward() * v;
    if (key(GLFW_KEY_S)) camera.position -= camera.forward() * v;
    if (key(GLFW_KEY_D)) camera.position += camera.right() * v;
    if (key(GLFW_KEY_A)) camera.position -= camera.right() * v;
    if (key(GLFW_KEY_E)) camera.position.z += v;
    if (key(GLFW_KEY_Q)) camera.position.z -= v;
  }
};

// The wheel scales the walking speed, or the orbit distance; the navigator is the window's user
// pointer.
void onScroll(GLFWwindow* window, double, double dy) {
  auto* nav = static_cast<Navigator*>(glfwGetWindowUserPointer(window));
  if (!nav || ImGui::GetIO().WantCaptureMouse) return;
  const double factor = std::pow(1.25, dy);
  if (nav->orbit) nav->orbit_distance /= factor;
  else nav->speed_mps *= factor;
}

// The window with a GL 4.5 core context and the ImGui overlay, torn down in reverse order.
class ViewerWindow {
 public:
  // `quad_buffered`: a stereo context (a left and a right back buffer), or an error saying the
  // display has none.
  ViewerWindow(int width, int height, bool quad_buffered) {
    glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 4);
    glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 5);
    glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
    glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_TRUE);
    glfwWindowHint(GLFW_STEREO, quad_buffered ? GLFW_TRUE : GLFW_FALSE);
    window_ = glfwCreateWindow(width, height, "TeraWalk", nullptr, nullptr);
    if (!window_ && quad_buffered)
      throw std::runtime_error(
          "--stereo quad-buffered: this display offers no quad-buffered stereo GL context; use "
          "side-by-side, top-bottom or anaglyph");
    if (!window_) throw std::runtime_error("GLFW: cannot create a GL 4.5 core window");
    glfwMakeContextCurrent(window_);
    glfwSwapInterval(0);
    IMGUI_CHECKVERSION();
    ImGui::CreateContext();
    ImGui::GetIO().IniFilename = nullptr;
    ImGui_ImplGlfw_InitForOpenGL(window_, true);
    ImGui_ImplOpenGL3_Init("#version 450");
  }
  ~ViewerWindow() {
    ImGui_ImplOpenGL3_Shutdown();
    ImGui_ImplGlfw_Shutdown();
    ImGui::DestroyContext();
    glfwDestroyWindow(window_);
  }
  ViewerWindow(const ViewerWindow&) = delete;
  ViewerWindow& operator=(const ViewerWindow&) = delete;
  GLFWwindow* get() const { return window_; }

 private:
  GLFWwindow* window_ = nullptr;
};

// What the panel sets, applied to the camera and the walkthrough before each frame.
struct ViewSettings {
  float tau = 1.0f;
  float fov_deg = 60.0f;
  float near_m = 0.05f, far_m = 1000.0f;
  float min_feature = 1.0f;
  int occlusion_mode = 0;
  int parametric_mode = 0;
  int stereo_mode = 0;  // StereoMode
  bool quad_buffered = false;  // the window has a stereo context
  float eye_separation_m = 0.065f;
  float zero_parallax_m = 10.0f;
};

// Keys that act once per press (not while held), unless the overlay has the keyboard.
class KeyPresses {
 public:
  explicit KeyPresses(GLFWwindow* window) : window_(window) {}
  bool pressed(int key) {
    const bool down = glfwGetKey(window_, key) == GLFW_PRESS;
    const bool edge = down && !latch_[key];
    latch_[key] = down;
    return edge && !ImGui::GetIO().WantCaptureKeyboard;
  }

 private:
  GLFWwindow* window_;
  bool latch_[512] = {};
};

// The camera-path recorder (R starts and stops): keys at the frames' times, written on stop.
struct PathRecorder {
  CameraPath path;
  bool on = false;

  void toggle(const std::string& file) {
    on = !on;
    if (!on && !path.keys.empty()) {
      writeCameraPath(path, file);
      std::fprintf(stderr, "view: recorded %zu keys to %s\n", path.keys.size(), file.c_str());
    }
    if (on) path.keys.clear();
  }
  void add(double t, const Camera& camera) {
    if (on && (path.keys.empty() || t > path.keys.back().time_s + 1e-3))
      path.keys.push_back({t, camera});
  }
};

// The frame's statistics, and the settings' controls under a header that opens them.
void drawStatsPanel(const FrameStats& stats, ViewSettings& settings, const Navigator& nav,
                    bool recording) {
  ImGui::SetNextWindowPos(ImVec2(8, 8), ImGuiCond_FirstUseEver);
  ImGui::Begin("TeraWalk", nullptr, ImGuiWindowFlags_AlwaysAutoResize);
  ImGui::Text("%.1f ms  (%.0f fps)   cut %.2f ms   gpu %.2f ms", stats.frame_ms,
              stats.frame_ms > 0 ? 1000.0 / stats.frame_ms : 0.0, stats.cpu_cut_ms, stats.gpu_ms);
  ImGui::Text("triangles %llu   clusters %u   visited %u",
              static_cast<unsigned long long>(stats.triangles_drawn), stats.nodes_drawn,
              stats.nodes_visited);
  ImGui::Text("pages resident %u  queued %u  loaded %u   fallbacks %u", stats.pages_resident,
              stats.pages_requested, stats.pages_loaded, stats.ancestor_fallbacks);
  ImGui::Text("GPU pool %.0f MiB   RSS %.0f MiB", stats.gpu_bytes_used / 1048576.0,
              stats.rss_bytes / 1048576.0);
  ImGui::Text("occlusion culled %u   pass1 %u  pass2 %u   occluders %u   cell %lld",
              stats.occlusion_culled, stats.pass1_clusters, stats.pass2_clusters,
              stats.occluders_drawn, static_cast<long long>(stats.view_cell));
  ImGui::Text("HZB build %.2f ms   test %.2f ms", stats.hzb_build_ms, stats.hzb_test_ms);
  ImGui::Text("parametric clusters %u   instances %llu   mesh triangles %llu   %.2f ms",
              stats.parametric_clusters_drawn,
              static_cast<unsigned long long>(stats.parametric_instances_drawn),
              static_cast<unsigned long long>(stats.parametric_triangles), stats.parametric_cpu_ms);
  if (stats.parametric_skipped > 0)
    ImGui::TextColored(ImVec4(1, 0.7f, 0.2f, 1), "parametric clusters not drawn: %u",
                       stats.parametric_skipped);
  if (!ImGui::CollapsingHeader("Settings")) {
    ImGui::Text("%s  speed %.1f m/s   [O] orbit  [R] record%s  [F12] screenshot",
                nav.orbit ? "orbit" : "walk", nav.speed_mps, recording ? " (on)" : "");
    ImGui::End();
    return;
  }
  ImGui::SliderFloat("tau (px)", &settings.tau, 0.25f, 64.0f, "%.2f", ImGuiSliderFlags_Logarithmic);
  ImGui::SliderFloat("FOV (deg)", &settings.fov_deg, 20.0f, 120.0f, "%.0f");
  ImGui::SliderFloat("near (m)", &settings.near_m, 0.01f, 10.0f, "%.2f",
                     ImGuiSliderFlags_Logarithmic);
  ImGui::SliderFloat("far (m)", &settings.far_m, 100.0f, 1e6f, "%.0f",
                     ImGuiSliderFlags_Logarithmic);
  ImGui::SliderFloat("min feature (px)", &settings.min_feature, 0.0f, 8.0f, "%.1f");
  static_assert(int(OcclusionMode::Off) == 0 && int(OcclusionMode::Hzb) == 1 &&
                int(OcclusionMode::Pvs) == 2, "the combo lists the modes in enum order");
  const char* const occlusion_names[] = {"off", "hzb", "pvs"};
  ImGui::Combo("occlusion", &settings.occlusion_mode, occlusion_names, 3);
  static_assert(int(ParametricMode::Impostor) == 0 && int(ParametricMode::Tessellated) == 1 &&
                int(ParametricMode::Off) == 2, "the combo lists the modes in enum order");
  const char* const parametric_names[] = {"impostor", "tessellated", "off"};
  ImGui::Combo("parametrics [P]", &settings.parametric_mode, parametric_names, 3);
  static_assert(int(StereoMode::Off) == 0 && int(StereoMode::SideBySide) == 1 &&
                int(StereoMode::TopBottom) == 2 && int(StereoMode::Anaglyph) == 3,
                "the combo lists the modes in enum order");
  // Quad-buffered only where the window was made with a stereo context (--stereo quad-buffered).
  static_assert(int(StereoMode::QuadBuffered) == 4, "the combo lists the modes in enum order");
  const char* const stereo_names[] = {"off", "side by side", "top and bottom", "anaglyph (red-cyan)",
                                      "quad-buffered"};
  ImGui::Combo("stereo", &settings.stereo_mode, stereo_names, settings.quad_buffered ? 5 : 4);
  ImGui::SliderFloat("eye separation (m)", &settings.eye_separation_m, 0.0f, 5.0f, "%.3f",
                     ImGuiSliderFlags_Logarithmic);
  ImGui::SliderFloat("zero parallax (m)", &settings.zero_parallax_m, 0.5f, 1000.0f, "%.1f",
                     ImGuiSliderFlags_Logarithmic);
  ImGui::Text("%s  speed %.1f m/s   [O] orbit  [R] record%s  [F12] screenshot",
              nav.orbit ? "orbit" : "walk", nav.speed_mps, recording ? " (on)" : "");
  ImGui::End();
}

// The overlay's windows: statistics and settings (top left), properties (top right), review
// (left, below the statistics, as tall as the window allows; it scrolls).
void drawOverlay(const FrameStats& stats, ViewSettings& settings, const Navigator& nav,
                 bool recording, const ViewSelection& selection, ViewReview& review,
                 ViewEdits& edits, ViewSections& sections, ViewViewpoints& viewpoints,
                 ViewMeasure& measure, ViewEnvironment& environment, ViewPath& player,
                 const CameraPath& recorded, Camera& camera, double now_s, int window_width,
                 int window_height) {
  ImGui_ImplOpenGL3_NewFrame();
  ImGui_ImplGlfw_NewFrame();
  ImGui::NewFrame();
  drawStatsPanel(stats, settings, nav, recording);
  selection.drawPanel(float(window_width) - 8.0f, 8.0f);
  review.drawPanel(8.0f, 200.0f, std::max(200.0f, float(window_height) - 208.0f));
  edits.drawPanel(now_s);
  sections.drawPanel();
  measure.drawPanel();
  environment.drawPanel();
  player.drawPanel(recorded);
  measure.draw(camera, window_width, window_height);
  const Camera current = camera;
  viewpoints.drawPanel(camera, current);
  edits.drawGizmo(camera, window_width, window_height);
  ImGui::Render();
  ImGui_ImplOpenGL3_RenderDrawData(ImGui::GetDrawData());
}

// Left-button clicks: a press and release within a few pixels (a longer drag looks around), and
// double clicks (a second click within 0.35 s, near the first). Window pixels, top left.
class ClickDetector {
 public:
  struct Click {
    int x, y;
    bool ctrl, twice;
  };
  // `mouse_taken`: the press went to the gizmo, so its release is no click.
  std::optional<Click> update(GLFWwindow* window, double now_s, bool mouse_taken) {
    double x = 0.0, y = 0.0;
    glfwGetCursorPos(window, &x, &y);
    const bool down = glfwGetMouseButton(window, GLFW_MOUSE_BUTTON_LEFT) == GLFW_PRESS;
    std::optional<Click> click;
    if (down && !was_down_) {
      press_x_ = x;
      press_y_ = y;
      pressed_over_ui_ = ImGui::GetIO().WantCaptureMouse || mouse_taken;
    } else if (!down && was_down_ && !pressed_over_ui_ &&
               std::abs(x - press_x_) + std::abs(y - press_y_) < 4.0) {
      const bool ctrl = glfwGetKey(window, GLFW_KEY_LEFT_CONTROL) == GLFW_PRESS ||
                        glfwGetKey(window, GLFW_KEY_RIGHT_CONTROL) == GLFW_PRESS;
      const bool twice = now_s - last_click_s_ < 0.35 && std::abs(x - last_x_) < 4.0 &&
                         std::abs(y - last_y_) < 4.0;
      click = Click{int(x), int(y), ctrl, twice};
      last_click_s_ = twice ? -1.0 : now_s;
      last_x_ = x;
      last_y_ = y;
    }
    was_down_ = down;
    return click;
  }

 private:
  bool was_down_ = false, pressed_over_ui_ = false;
  double press_x_ = 0.0, press_y_ = 0.0, last_x_ = 0.0, last_y_ = 0.0;
  double last_click_s_ = -1.0;
};

// Double click, or "zoom to" the review's results: the camera backs off along its view until the
// box fills about two thirds of the image; orbit mode circles the box from then on.
void frameBox(const glm::dvec3& lo, const glm::dvec3& hi, Camera& camera, Navigator& nav) {
  const glm::dvec3 centre = 0.5 * (lo + hi);
  const double radius = std::max(0.5 * glm::length(hi - lo), 0.05);
  const double distance = 1.5 * radius / std::tan(0.5 * camera.fov_y_rad);
  camera.position = centre - camera.forward() * distance;
  nav.orbit_target = centre;
  nav.orbit_distance = distance;
}

void frameSelection(const ViewSelection& selection, Camera& camera, Navigator& nav) {
  glm::dvec3 lo, hi;
  if (selection.bounds(lo, hi)) frameBox(lo, hi, camera, nav);
}

// A review action of a script, done as the panel's button does it.
void runReviewAction(ViewReview& review, const ViewEvent& e) {
  uint32_t layer = 0;
  const std::string& a = e.action;
  if (a == "hide-layer" || a == "show-layer" || a == "isolate-layer" || a == "xray-others") {
    if (!review.layerNamed(e.text, layer)) return;
    if (a == "hide-layer" || a == "show-layer") review.setLayerHidden(layer, a == "hide-layer");
    else if (a == "isolate-layer") review.isolateLayer(layer);
    else review.xrayOthers(layer);
  } else if (a == "show-all") {
    review.showAll();
  } else if (a == "search") {
    review.search(e.text);
  } else if (a == "query") {
    review.query(e.text, {});
  } else if (a == "select-results") {
    review.selectResults();
  } else if (a == "isolate-results") {
    review.isolateResults();
  } else if (a == "zoom-results") {
    review.zoomToResults();
  } else if (a == "save-selection") {
    review.saveSelection(e.text);
  } else if (a == "save-visibility") {
    review.saveVisibility(e.text);
  } else if (a == "restore") {
    review.restore(e.text);
  }
}

// An edit of a script, done as the gizmo or the Edit panel does it. `toFramebuffer` turns window
// pixels into framebuffer pixels, the gizmo's.
void runEditAction(ViewEdits& edits, const ViewEvent& e, const Camera& camera, int fb_w, int fb_h,
                   double now_s, const std::function<glm::dvec2(double, double)>& toFramebuffer) {
  const std::string& a = e.action;
  auto number = [&](const std::string& text) {
    try {
      return std::stod(text);
    } catch (const std::exception&) {
      std::fprintf(stderr, "terawalk: %s: '%s' is not a number\n", a.c_str(), text.c_str());
      return std::nan("");
    }
  };
  if (a == "move") {
    try {
      edits.moveSelection(parseVec3(e.text));
    } catch (const std::exception& error) {
      std::fprintf(stderr, "terawalk: move: %s\n", error.what());
    }
  } else if (a == "rotate") {
    if (const double d = number(e.text); std::isfinite(d)) edits.rotateSelection({0, 0, 1}, d);
  } else if (a == "scale") {
    if (const double f = number(e.text); std::isfinite(f)) edits.scaleSelection(f);
  } else if (a == "explode") {
    if (const double f = number(e.text); std::isfinite(f)) edits.explode(f, now_s);
  } else if (a == "collapse") {
    edits.collapse(now_s);
  } else if (a == "hide-selection") {
    edits.hideSelection();
  } else if (a == "comment") {
    edits.commentSelection(e.text);
  } else if (a == "undo") {
    edits.undo();
  } else if (a == "redo") {
    edits.redo();
  } else if (a == "save-changes") {
    edits.save();
  } else if (a == "gizmo") {
    edits.toggleGizmo();
  } else if (a == "drag") {
    double x0, y0, x1, y1;
    if (std::sscanf(e.text.c_str(), "%lf %lf %lf %lf", &x0, &y0, &x1, &y1) != 4) {
      std::fprintf(stderr, "terawalk: drag: expected X0 Y0 X1 Y1, got '%s'\n", e.text.c_str());
      return;
    }
    const glm::dvec2 p0 = toFramebuffer(x0, y0), p1 = toFramebuffer(x1, y1);
    if (!edits.press(camera, fb_w, fb_h, p0.x, p0.y)) {
      std::printf("edits: drag at %.0f,%.0f: no gizmo handle there\n", x0, y0);
      return;
    }
    edits.dragTo(p1.x, p1.y);
    edits.release();
  }
}

// A section action of a script (view_sections.h).
void runSectionAction(ViewSections& sections, const ViewEvent& e, const Camera& camera,
                      const std::function<glm::dvec2(double, double)>& toFramebuffer) {
  const std::string& a = e.action;
  try {
    if (a == "section-at") {
      double x = 0.0, y = 0.0;
      if (std::sscanf(e.text.c_str(), "%lf %lf", &x, &y) != 2)
        throw std::invalid_argument("expected X Y, got '" + e.text + "'");
      const glm::dvec2 p = toFramebuffer(x, y);
      sections.placeAt(camera, int(p.x), int(p.y));
    } else if (a == "section") {
      sections.add(parseSectionPlane(e.text));
    } else if (a == "section-offset") {
      sections.offsetLast(std::stod(e.text));
    } else if (a == "section-box") {
      sections.boxAroundSelection(0.05);
    } else if (a == "section-clear") {
      sections.clear();
    }
  } catch (const std::exception& error) {
    std::fprintf(stderr, "terawalk: %s: %s\n", a.c_str(), error.what());
  }
}

bool isSectionAction(const std::string& a) {
  return a == "section-at" || a == "section" || a == "section-offset" || a == "section-box" ||
         a == "section-clear";
}

bool isEditAction(const std::string& a) {
  for (const char* edit : {"move", "rotate", "scale", "explode", "collapse", "hide-selection",
                           "comment", "undo", "redo", "save-changes", "drag", "gizmo"})
    if (a == edit) return true;
  return false;
}

WalkthroughOptions viewOptions(const ViewArgs& args, GLFWwindow* window) {
  WalkthroughOptions options;
  glfwGetFramebufferSize(window, &options.width, &options.height);
  options.tau_px = args.tau_px;
  options.target_fps = args.target_fps;
  options.finish_each_frame = false;
  options.occlusion = parseOcclusionMode(args.occlusion);
  options.parametrics = parseParametricMode(args.parametrics);
  options.pager.gpu_budget_bytes = parseByteSize(args.gpu_budget, "--gpu-budget");
  return options;
}

// The loop, frame after frame: input, the camera (replayed or navigated), the settings applied,
// the frame rendered and shown with the overlay on top.
void runViewLoop(const ViewArgs& args, GLFWwindow* window, Walkthrough& walk,
                 const WalkthroughOptions& options, const ProjectDatabase* db) {
  Aabb bounds;
  bounds.add(walk.worldMin());
  bounds.add(walk.worldMax());
  const double diagonal = glm::length(bounds.max - bounds.min);
  Navigator nav;
  glfwSetWindowUserPointer(window, &nav);
  glfwSetScrollCallback(window, onScroll);
  nav.speed_mps = std::max(1.0, diagonal / 30.0);
  nav.orbit_target = 0.5 * (bounds.min + bounds.max);
  nav.orbit_distance = diagonal;

  CameraPath replay;
  if (!args.path_file.empty()) replay = readCameraPath(args.path_file);
  Camera camera = generateOrbitPath(bounds, 2).sample(0.0);
  camera.near_m = 0.05;
  camera.far_m = std::max(100.0, 10.0 * diagonal);
  if (!replay.keys.empty()) camera = replay.sample(replay.keys.front().time_s, camera);

  PathRecorder recorder;
  ViewPath player;
  player.load(replay, args.path_file);
  ViewSettings settings;
  settings.tau = float(walk.tau());
  settings.fov_deg = float(glm::degrees(camera.fov_y_rad));
  settings.near_m = float(camera.near_m);
  settings.far_m = float(camera.far_m);
  settings.occlusion_mode = static_cast<int>(options.occlusion);
  settings.parametric_mode = static_cast<int>(walk.parametrics());  // auto is resolved by now
  settings.stereo_mode = static_cast<int>(args.stereo.mode);
  settings.quad_buffered = args.stereo.mode == StereoMode::QuadBuffered;
  settings.eye_separation_m = float(args.stereo.eye_separation_m);
  settings.zero_parallax_m = float(args.stereo.zero_parallax_m);
  ViewStereo stereo_screen;
  int shot = 0;
  KeyPresses keys(window);
  ViewSelection selection(walk.package(), walk.objectStates(), db);
  ViewReview review(walk.package(), walk.objectStates(), selection, db,
                    selectionSetsPathFor(args.file));
  const char* user = std::getenv("USER");
  ViewEdits edits(walk, selection, changeSetPathFor(args.file), user && *user ? user : "terawalk");
  ViewSections sections(walk, selection);
  const glm::dvec3 model_centre = 0.5 * (walk.worldMin() + walk.worldMax());
  ViewEnvironment environment(walk, environmentOptions(args.environment, model_centre), model_centre);
  ViewMeasure measure(walk, selection, [&edits](const std::string& key) { return edits.placement(key); });
  ViewViewpoints viewpoints(walk, selection, sections, reviewArchivePathFor(args.file),
                            user && *user ? user : "terawalk");
  ClickDetector clicks;
  const std::vector<ViewEvent> script =
      args.script.empty() ? std::vector<ViewEvent>{} : readViewScript(args.script);
  size_t next_event = 0;
  int script_delay = 0;   // frames the script waited at its `settle` events
  int steady_frames = 0;  // frames running with every page the cut wants drawn
  bool quit = false;
  bool mouse_was_down = false;

  using Clock = std::chrono::steady_clock;
  const auto start = Clock::now();
  auto last = start;
  FrameStats stats;
  for (int frame = 0; !glfwWindowShouldClose(window); ++frame) {
    glfwPollEvents();
    const auto now = Clock::now();
    const double dt = std::chrono::duration<double>(now - last).count();
    const double t = std::chrono::duration<double>(now - start).count();
    last = now;

    if (keys.pressed(GLFW_KEY_O)) {
      nav.orbit = !nav.orbit;
      if (nav.orbit) nav.orbit_distance = glm::length(camera.position - nav.orbit_target);
    }
    if (keys.pressed(GLFW_KEY_P)) settings.parametric_mode = (settings.parametric_mode + 1) % 3;
    if (keys.pressed(GLFW_KEY_R)) recorder.toggle(args.record_file);
    if (keys.pressed(GLFW_KEY_G)) edits.toggleGizmo();
    if (keys.pressed(GLFW_KEY_M)) measure.toggle();
    // Esc clears the selection; with nothing selected, it quits.
    auto escape = [&] {
      if (selection.empty()) glfwSetWindowShouldClose(window, GLFW_TRUE);
      else selection.clear();
    };
    if (keys.pressed(GLFW_KEY_ESCAPE)) escape();

    if (player.following())
      player.update(dt, camera);
    else
      nav.update(window, camera, dt, edits.capturing());
    camera.fov_y_rad = glm::radians(double(settings.fov_deg));
    camera.near_m = settings.near_m;
    camera.far_m = settings.far_m;
    recorder.add(t, camera);

    int fb_w = 0, fb_h = 0;
    glfwGetFramebufferSize(window, &fb_w, &fb_h);
    // In stereo the renderer draws one eye at a time, at the eye's size.
    StereoOptions stereo;
    stereo.mode = static_cast<StereoMode>(settings.stereo_mode);
    stereo.eye_separation_m = settings.eye_separation_m;
    stereo.zero_parallax_m = std::max(0.01f, settings.zero_parallax_m);
    int eye_w = fb_w, eye_h = fb_h;
    stereoEyeSize(stereo.mode, fb_w, fb_h, eye_w, eye_h);
    if (eye_w > 0 && eye_h > 0 && (eye_w != walk.renderer().width() || eye_h != walk.renderer().height()))
      walk.renderer().resize(eye_w, eye_h);
    if (options.target_fps <= 0.0) walk.setTau(settings.tau);
    walk.setMinFeaturePx(settings.min_feature);
    walk.setOcclusion(static_cast<OcclusionMode>(settings.occlusion_mode));
    walk.setParametrics(static_cast<ParametricMode>(settings.parametric_mode));
    edits.update(t);
    stats = stereo.mode == StereoMode::Off ? walk.renderFrame(camera, t)
                                           : stereo_screen.render(walk, camera, t, stereo);
    settings.tau = float(walk.tau());
    steady_frames = stats.ancestor_fallbacks == 0 && stats.pages_requested == 0 ? steady_frames + 1 : 0;

    // Clicks pick in the frame just drawn, from the mouse and from the script.
    int win_w = 0, win_h = 0;
    glfwGetWindowSize(window, &win_w, &win_h);
    auto toFramebuffer = [&](double x, double y) {
      return glm::dvec2(win_w > 0 ? x * fb_w / win_w : x, win_h > 0 ? y * fb_h / win_h : y);
    };
    // The gizmo takes a press on one of its handles, and the mouse until the button is up.
    {
      double mx = 0.0, my = 0.0;
      glfwGetCursorPos(window, &mx, &my);
      const glm::dvec2 m = toFramebuffer(mx, my);
      const bool down = glfwGetMouseButton(window, GLFW_MOUSE_BUTTON_LEFT) == GLFW_PRESS;
      if (down && !mouse_was_down && !ImGui::GetIO().WantCaptureMouse)
        edits.press(camera, fb_w, fb_h, m.x, m.y);
      else if (down && edits.capturing())
        edits.dragTo(m.x, m.y);
      else if (!down)
        edits.release();
      mouse_was_down = down;
    }
    auto pickAt = [&](int x, int y, bool ctrl, bool twice) {
      int px = win_w > 0 ? x * fb_w / win_w : x, py = win_h > 0 ? y * fb_h / win_h : y;
      // In stereo the ids are the right eye's: a click picks at the same place of its eye.
      if (stereo.mode == StereoMode::SideBySide && eye_w > 0) px %= eye_w;
      if (stereo.mode == StereoMode::TopBottom && eye_h > 0) py %= eye_h;
      if (px < 0 || py < 0 || px >= walk.renderer().width() || py >= walk.renderer().height())
        return;
      if (measure.on()) {  // M: clicks place measure points
        measure.addPoint(camera, px, py);
        return;
      }
      if (sections.placingOnClick()) {  // the Sections panel's "Plane at click"
        sections.placeAt(camera, px, py);
        return;
      }
      selection.click(pickPixel(walk.renderer(), camera, px, py), ctrl);
      if (twice) frameSelection(selection, camera, nav);
    };
    if (const auto click = clicks.update(window, t, edits.capturing()))
      pickAt(click->x, click->y, click->ctrl, click->twice);
    for (; next_event < script.size() && script[next_event].frame + script_delay <= frame; ++next_event) {
      const ViewEvent& e = script[next_event];
      if (e.kind == ViewEvent::Kind::Settle) {
        if (steady_frames < 3) break;  // held: this event again next frame
        script_delay = frame - e.frame;
        viewSay("view: settled at frame %d\n", frame);
        continue;
      }
      switch (e.kind) {
        case ViewEvent::Kind::Click: pickAt(e.x, e.y, false, false); break;
        case ViewEvent::Kind::CtrlClick: pickAt(e.x, e.y, true, false); break;
        case ViewEvent::Kind::DoubleClick: pickAt(e.x, e.y, false, true); break;
        case ViewEvent::Kind::Quit: quit = true; break;
        case ViewEvent::Kind::Settle: break;  // above
        case ViewEvent::Kind::Review:
          if (e.action == "measure-at") {
            double x = 0.0, y = 0.0;
            if (std::sscanf(e.text.c_str(), "%lf %lf", &x, &y) == 2) {
              const glm::dvec2 p = toFramebuffer(x, y);
              measure.addPoint(camera, int(p.x), int(p.y));
            }
          } else if (e.action == "measure-between")
            measure.between(false);
          else if (e.action == "measure-centre-lines")
            measure.between(true);
          else if (e.action == "measure-clear")
            measure.clear();
          else if (e.action == "path-play")
            player.play();
          else if (e.action == "path-pause")
            player.pause();
          else if (e.action == "path-seek")
            player.seek(std::atof(e.text.c_str()));
          else if (e.action == "path-smooth")
            player.smooth(std::atof(e.text.c_str()));
          else if (e.action == "path-save")
            player.save(e.text);
          else if (e.action == "ocean")
            environment.setOcean(e.text == "on");
          else if (e.action == "sky")
            environment.setSky(e.text == "on");
          else if (e.action == "save-viewpoint")
            viewpoints.save(e.text, camera);
          else if (e.action == "go-viewpoint")
            viewpoints.go(e.text, camera);
          else if (isSectionAction(e.action))
            runSectionAction(sections, e, camera, toFramebuffer);
          else if (isEditAction(e.action))
            runEditAction(edits, e, camera, fb_w, fb_h, t, toFramebuffer);
          else
            runReviewAction(review, e);
          break;
        case ViewEvent::Kind::Key:
          if (e.key == GLFW_KEY_ESCAPE) escape();
          if (e.key == GLFW_KEY_O) nav.orbit = !nav.orbit;
          if (e.key == GLFW_KEY_P) settings.parametric_mode = (settings.parametric_mode + 1) % 3;
          if (e.key == GLFW_KEY_R) recorder.toggle(args.record_file);
          if (e.key == GLFW_KEY_F12) saveScreenshot(walk.renderer(), "terawalk-script.png");
          break;
      }
    }

    if (glm::dvec3 lo, hi; review.takeZoomRequest(lo, hi)) frameBox(lo, hi, camera, nav);
    if (keys.pressed(GLFW_KEY_F12)) {
      char name[64];
      std::snprintf(name, sizeof name, "terawalk-%03d.png", shot++);
      saveScreenshot(walk.renderer(), name);
    }
    if (stereo.mode == StereoMode::Off)
      walk.renderer().blitToScreen(fb_w, fb_h);
    else
      stereo_screen.present(fb_w, fb_h);
    drawOverlay(stats, settings, nav, recorder.on, selection, review, edits, sections, viewpoints,
                measure, environment, player, recorder.path, camera, t, fb_w, fb_h);
    glfwSwapBuffers(window);

    if (quit || (args.frames > 0 && frame + 1 >= args.frames)) {
      if (!args.screenshot.empty()) saveScreenshot(walk.renderer(), args.screenshot);
      break;
    }
  }
  if (recorder.on && !recorder.path.keys.empty())
    writeCameraPath(recorder.path, args.record_file);
  glfwSetWindowUserPointer(window, nullptr);
}

void runView(ViewArgs args) {
  int width = 0, height = 0;
  parseImageSize(args.size, "--size", width, height);
  args.stereo = stereoOptions(args.stereo_args);
  GlfwSession glfw;
  ViewerWindow window(width, height, args.stereo.mode == StereoMode::QuadBuffered);
  const WalkthroughOptions options = viewOptions(args, window.get());
  Walkthrough walk(args.file, options);
  const std::optional<ProjectDatabase> db = openPackageDatabase(args.file, walk.package(), args.db);
  runViewLoop(args, window.get(), walk, options, db ? &*db : nullptr);
}

}  // namespace

void registerViewCommand(CLI::App& app, const GlobalOptions&) {
  auto args = std::make_shared<ViewArgs>();
  CLI::App* cmd = app.add_subcommand("view", "Walk through a package in a window (GLFW)");
  cmd->add_option("file", args->file, "Package (.twk)")->required()->check(CLI::ExistingFile);
  cmd->add_option("--size", args->size, "Window size WIDTHxHEIGHT")->capture_default_str();
  cmd->add_option("--path", args->path_file, "Replay this camera path (loops)")
      ->check(CLI::ExistingFile);
  cmd->add_option("--record", args->record_file, "File the R key records the camera path to")
      ->capture_default_str();
  cmd->add_option("--gpu-budget", args->gpu_budget, "GPU geometry pool size")->capture_default_str();
  cmd->add_option("--tau", args->tau_px, "Screen-space error threshold, pixels")
      ->capture_default_str();
  cmd->add_option("--target-fps", args->target_fps, "Adapt tau to hold this frame rate");
  cmd->add_option("--frames", args->frames, "Quit after this many frames (scripted runs)");
  cmd->add_option("--screenshot", args->screenshot, "With --frames: save the last frame here");
  cmd->add_option("--db", args->db,
                  "Project database (SQLite): the picked object's record; default: the one the "
                  "package names")
      ->check(CLI::ExistingFile);
  cmd->add_option("--script", args->script,
                  "Clicks and keys at given frames: FRAME click X Y, ctrl-click, double-click, "
                  "key NAME, quit")
      ->check(CLI::ExistingFile);
  cmd->add_option("--occlusion", args->occlusion, "Occlusion culling at start: off, hzb, pvs")
      ->check(CLI::IsMember({"off", "hzb", "pvs"}))
      ->capture_default_str();
  cmd->add_option("--parametrics", args->parametrics,
                  "Parametric objects at start: impostor, tessellated, off, auto (tessellated on "
                  "llvmpipe, impostor on GPUs; P cycles)")
      ->check(CLI::IsMember({"impostor", "tessellated", "off", "auto"}))
      ->capture_default_str();
  addEnvironmentOptions(*cmd, args->environment);
  addStereoOptions(*cmd, args->stereo_args,
                   "Stereo at start: off, side-by-side, top-bottom, anaglyph, quad-buffered (where "
                   "the display offers it); the Settings panel changes it, the eye separation and "
                   "the zero-parallax distance");
  cmd->callback([args] { runView(*args); });
}

}  // namespace tw

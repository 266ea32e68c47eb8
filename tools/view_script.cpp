// Reading viewer scripts; see view_script.h.
#include "view_script.h"

#include <GLFW/glfw3.h>

#include <algorithm>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace tw {
namespace {

int keyCode(const std::string& name) {
  if (name == "escape") return GLFW_KEY_ESCAPE;
  if (name == "o") return GLFW_KEY_O;
  if (name == "p") return GLFW_KEY_P;
  if (name == "r") return GLFW_KEY_R;
  if (name == "f12") return GLFW_KEY_F12;
  return -1;
}

}  // namespace

bool reviewActionTakesText(const std::string& action, bool& takes_text) {
  static const char* const with_text[] = {"hide-layer", "show-layer", "isolate-layer",
                                          "xray-others", "search", "query", "save-selection",
                                          "save-visibility", "restore", "move", "rotate", "scale",
                                          "explode", "comment", "drag", "section-at", "section",
                                          "section-offset", "save-viewpoint", "go-viewpoint",
                                          "measure-at", "ocean", "sky", "path-seek",
                                          "path-smooth", "path-save"};
  static const char* const without_text[] = {"show-all", "select-results", "isolate-results",
                                             "zoom-results", "undo", "redo", "save-changes",
                                             "collapse", "hide-selection", "gizmo", "section-box",
                                             "section-clear", "measure-between",
                                             "measure-centre-lines", "measure-clear",
                                             "path-play", "path-pause"};
  for (const char* a : with_text)
    if (action == a) return takes_text = true;
  for (const char* a : without_text)
    if (action == a) {
      takes_text = false;
      return true;
    }
  return false;
}

std::vector<ViewEvent> readViewScript(const std::filesystem::path& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error(path.string() + ": cannot open the viewer script");
  std::vector<ViewEvent> events;
  std::string line;
  for (int number = 1; std::getline(in, line); ++number) {
    auto fail = [&](const std::string& why) {
      throw std::runtime_error(path.string() + ":" + std::to_string(number) + ": " + why);
    };
    const size_t hash = line.find('#');
    if (hash != std::string::npos) line.resize(hash);
    std::istringstream words(line);
    ViewEvent e;
    std::string kind;
    if (!(words >> e.frame)) {
      if (line.find_first_not_of(" \t\r") != std::string::npos) fail("expected a frame number");
      continue;
    }
    if (e.frame < 0) fail("the frame number is negative");
    if (!(words >> kind)) fail("expected an event after the frame number");
    if (kind == "click" || kind == "ctrl-click" || kind == "double-click") {
      e.kind = kind == "click"        ? ViewEvent::Kind::Click
               : kind == "ctrl-click" ? ViewEvent::Kind::CtrlClick
                                      : ViewEvent::Kind::DoubleClick;
      if (!(words >> e.x >> e.y) || e.x < 0 || e.y < 0) fail("expected the pixel X Y");
    } else if (kind == "key") {
      std::string name;
      if (!(words >> name) || (e.key = keyCode(name)) < 0)
        fail("expected a key: escape, o, p, r or f12");
      e.kind = ViewEvent::Kind::Key;
    } else if (kind == "quit") {
      e.kind = ViewEvent::Kind::Quit;
    } else if (kind == "settle") {
      e.kind = ViewEvent::Kind::Settle;
    } else if (bool takes_text = false; reviewActionTakesText(kind, takes_text)) {
      e.kind = ViewEvent::Kind::Review;
      e.action = kind;
      if (takes_text) {
        std::getline(words >> std::ws, e.text);
        while (!e.text.empty() && (e.text.back() == ' ' || e.text.back() == '\r'))
          e.text.pop_back();
        if (e.text.empty()) fail("'" + kind + "' needs a text after it");
      }
    } else {
      fail("unknown event '" + kind +
           "' (click, ctrl-click, double-click, key, quit, settle, or a review action: hide-layer, "
           "show-layer, isolate-layer, xray-others, show-all, search, query, select-results, "
           "isolate-results, zoom-results, save-selection, save-visibility, restore)");
    }
    std::string extra;
    if (words >> extra) fail("unexpected '" + extra + "' at the end of the line");
    events.push_back(e);
  }
  std::stable_sort(events.begin(), events.end(),
                   [](const ViewEvent& a, const ViewEvent& b) { return a.frame < b.frame; });
  return events;
}

}  // namespace tw

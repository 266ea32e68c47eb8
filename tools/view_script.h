// A viewer script (`terawalk view --script FILE`): clicks and keys at given frames, so a run of
// the window can be repeated exactly (tests, demos, the pictures in docs/).
//
//   # comment
//   FRAME click X Y          select the object under window pixel X,Y (from the top left)
//   FRAME ctrl-click X Y     add it to the selection, or remove it
//   FRAME double-click X Y   select it and frame the selection
//   FRAME key NAME           escape, o, p, r, f12
//   FRAME quit
//   FRAME settle             hold the script until the view has settled (no page waiting, no
//                            coarser ancestor drawn for a missing page, three frames running);
//                            the later frame numbers count from the frame it settled at, so a
//                            slow machine sees the same pictures as a fast one
//
// and the review panel's actions (view_review.h), as its buttons do them; TEXT is the rest of
// the line:
//   FRAME hide-layer TEXT | show-layer TEXT | isolate-layer TEXT | xray-others TEXT
//   FRAME show-all
//   FRAME search TEXT        names and keys holding TEXT
//   FRAME query TEXT         a WHERE clause over the project database (no values bound)
//   FRAME select-results | isolate-results | zoom-results
//   FRAME save-selection TEXT | save-visibility TEXT | restore TEXT
// and the edits (view_edits.h) of the selection:
//   FRAME move DX,DY,DZ | rotate DEGREES (about Z) | scale FACTOR | explode FACTOR | collapse
//   FRAME drag X0 Y0 X1 Y1   a gizmo handle pressed at X0,Y0 and dragged to X1,Y1 (window pixels)
//   FRAME gizmo (switches it on or off) | hide-selection | comment TEXT | undo | redo | save-changes
// and the section planes (view_sections.h):
//   FRAME section-at X Y     a plane on the surface under window pixel X,Y, facing the eye
//   FRAME section X,Y,Z,NX,NY,NZ | section-offset METRES | section-box | section-clear
// and the named viewpoints (view_viewpoints.h):
//   FRAME save-viewpoint NAME | go-viewpoint NAME
// and the setting (view_environment.h):
//   FRAME ocean on|off | sky on|off
// and the path player (view_path.h):
//   FRAME path-play | path-pause | path-seek SECONDS | path-smooth INTERVAL | path-save FILE
// and measuring (view_measure.h):
//   FRAME measure-at X Y (a snapped point; two give a distance, three an angle)
//   FRAME measure-between | measure-centre-lines (the two selected objects) | measure-clear
//
// Events run after their frame is drawn, in file order.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

namespace tw {

struct ViewEvent {
  enum class Kind { Click, CtrlClick, DoubleClick, Key, Quit, Settle, Review };
  int frame = 0;
  Kind kind = Kind::Click;
  int x = 0, y = 0;  // clicks
  int key = 0;       // GLFW key code
  std::string action;  // Review: the action's name, as in the script
  std::string text;    // Review: its argument (layer, search text, query, set name)
};

// Review actions a script may name, and whether each takes TEXT.
bool reviewActionTakesText(const std::string& action, bool& takes_text);

// Throws std::runtime_error naming the file, the line and the reason.
std::vector<ViewEvent> readViewScript(const std::filesystem::path& path);

}  // namespace tw

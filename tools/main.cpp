// The `terawalk` executable: one binary, one subcommand per verb.
#include <cstdio>
#include <exception>

#include "command.h"

int main(int argc, char** argv) {
  tw::GlobalOptions global;
  CLI::App app{"TeraWalk: make huge CAD models walkable in real time", "terawalk"};
  app.require_subcommand(1);
  app.set_version_flag("--version", "terawalk 0.1.0");
  app.add_flag("-q,--quiet", global.quiet, "Print no progress");
  app.fallthrough();  // --quiet may also follow the verb
  tw::registerGenCommand(app, global);
  tw::registerInfoCommand(app, global);
  tw::registerPreprocessCommand(app, global);
  tw::registerSnapshotCommand(app, global);
  tw::registerVerifyCommand(app, global);
  tw::registerRenderCommand(app, global);
  tw::registerViewCommand(app, global);
  tw::registerCompareCommand(app, global);
  tw::registerBenchCommand(app, global);
  tw::registerPickCommand(app, global);
  tw::registerMeasureCommand(app, global);
  tw::registerFindCommand(app, global);
  tw::registerBcfCommand(app, global);
  tw::registerChangesCommand(app, global);
  tw::registerPathCommand(app, global);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "terawalk: error: %s\n", e.what());
    return 1;
  }
  return 0;
}

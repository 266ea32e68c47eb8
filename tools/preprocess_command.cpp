// `terawalk preprocess INPUT... -o model.twk`: the offline build of a walkable package; and the
// same build as the steps a scheduler runs (preprocess_steps.h): `preprocess plan`, `preprocess
// brick`, `preprocess merge`, and all three over Open MPI with `--mpi` (preprocess_mpi.h).
#include <algorithm>
#include <cctype>
#include <cstdio>
#include <cstdlib>
#include <optional>
#include <stdexcept>
#include <string>

#include "command.h"
#include "command_args.h"
#include "preprocess_driver.h"
#include "preprocess_mpi.h"
#include "preprocess_steps.h"
#include "ifc_properties.h"
#include "project_database.h"
#include "scene_io.h"

namespace tw {
namespace {

// IFC inputs carry what a reviewer reads when picking (class, storey, property sets): without
// --db, they go into a project database next to the package (model.twk -> model.db), which the
// package then names. Empty when no input is IFC.
std::filesystem::path ifcDatabase(const std::vector<std::filesystem::path>& inputs,
                                  const std::filesystem::path& output) {
  std::vector<std::filesystem::path> ifc;
  for (const auto& input : inputs)
    if (sceneFormatOf(input) == SceneFormat::Ifc) ifc.push_back(input);
  if (ifc.empty()) return {};
  std::filesystem::path db = output;
  db.replace_extension(".db");
  ProjectDatabase database = ProjectDatabase::create(db);
  uint64_t products = 0;
  for (const auto& input : ifc) products += writeIfcProperties(input, database);
  std::printf("database    %s: %llu IFC products with their property sets\n", db.string().c_str(),
              static_cast<unsigned long long>(products));
  return db;
}

struct PreprocessArgs {
  std::vector<std::string> inputs;
  std::string output;
  std::string work;
  bool mpi = false;
  std::string memory_budget = "2G";
  uint32_t threads = 0;
  uint32_t cluster_size = 256;
  uint32_t parametric_cluster_size = 64;
  uint64_t brick_triangles = 0;
  bool resume = false;
  bool keep_work = false;
  std::string visibility = "on";
  uint32_t visibility_rays = 1024;
  double view_cell_size_m = 0.0;
  std::string parametric_occluders = "on";
  std::vector<std::string> exclude_layers;
  std::string up = "auto";
  std::string cad_primitives = "on";
  double cad_tolerance_m = 0.0;
  std::string cad_bspline = "conforming";
  std::string db;
};

void printSummary(const PreprocessReport& r, const std::string& output) {
  std::printf("preprocess: %s\n", output.c_str());
  std::printf("  input       %llu triangles, %llu parametric instances, %llu objects\n",
              static_cast<unsigned long long>(r.input_triangles),
              static_cast<unsigned long long>(r.primitives),
              static_cast<unsigned long long>(r.objects));
  std::printf("  bricks      %u (%u reused%s)\n", r.bricks, r.bricks_reused,
              r.bricking_reused ? ", bricking reused" : "");
  if (r.bricks > 1)
    std::printf("  seams       %llu edges locked in both bricks, %llu rim positions welded onto "
                "another brick's\n",
                static_cast<unsigned long long>(r.seam_edges),
                static_cast<unsigned long long>(r.welded_across_bricks));
  std::printf("  levels      %zu:", r.triangles_per_level.size());
  for (uint64_t t : r.triangles_per_level) std::printf(" %llu", static_cast<unsigned long long>(t));
  std::printf(" triangles (root %llu)\n", static_cast<unsigned long long>(r.root_triangles));
  std::printf("  clusters    %llu mesh, %llu parametric (%u sorted runs on disk)\n",
              static_cast<unsigned long long>(r.clusters),
              static_cast<unsigned long long>(r.parametric_clusters), r.parametric_sort_runs);
  std::printf("  bricks held %llu root triangles for the merge",
              static_cast<unsigned long long>(r.merge_front_triangles));
  if (r.bricks > 1) std::printf(" (brick DAGs stop at level %u)", r.brick_stop_level);
  std::printf(", %llu shared positions for snapping\n",
              static_cast<unsigned long long>(r.shared_positions));
  const GroupMethodCounts& g = r.groups_by_method;
  auto count = [&](GroupMethod m) { return static_cast<unsigned long long>(g[size_t(m)]); };
  std::printf("  groups      %llu locked, %llu merged, %llu sloppy, %llu proxy, %llu dropped, "
              "%llu unchanged\n",
              count(GroupMethod::Locked), count(GroupMethod::Merged), count(GroupMethod::Sloppy),
              count(GroupMethod::Proxy), count(GroupMethod::Dropped),
              count(GroupMethod::PassThrough));
  std::printf("  repeats     %llu mesh triangles dropped as exact copies of another\n",
              static_cast<unsigned long long>(r.triangles_repeated));
  std::printf("  winding     %llu mesh triangles turned to agree with their piece\n",
              static_cast<unsigned long long>(r.triangles_turned));
  std::printf("  sealed runs %llu open parts, %llu closing cylinders\n",
              static_cast<unsigned long long>(r.sealed_run_members),
              static_cast<unsigned long long>(r.sealed_run_closers));
  std::printf("  box faces   %llu covered by another box's face\n",
              static_cast<unsigned long long>(r.covered_box_faces));
  for (const StageTime& s : r.stages) std::printf("  %-12s%9.3f s\n", s.name.c_str(), s.seconds);
  std::printf("  total       %8.2f s, %.2f M input triangles/s\n", r.seconds,
              r.seconds > 0 ? double(r.input_triangles) / r.seconds / 1e6 : 0.0);
  if (r.visibility.ran) {
    const VisibilitySummary& v = r.visibility;
    std::printf("  visibility  %u cells free, %u solid (%.2f m), %llu rays (%.1f M rays/s)\n",
                v.free_cells, v.solid_cells, v.cell_size_m, static_cast<unsigned long long>(v.rays),
                v.rays_per_second / 1e6);
    std::printf("              candidates level %u, %llu triangles; occluders %.1f, visible %.1f"
                " per cell; section %llu bytes\n",
                v.candidate_level, static_cast<unsigned long long>(v.candidate_triangles),
                v.average_occluders, v.average_visible,
                static_cast<unsigned long long>(v.section_bytes));
    if (v.parametric_clusters > 0)
      std::printf("              parametric: %llu of %llu instances sampled (%.3g m wide and"
                  " up, %llu triangles) in %llu clusters, %llu of them whole\n",
                  static_cast<unsigned long long>(v.parametric_instances),
                  static_cast<unsigned long long>(v.parametric_instances_total),
                  double(v.parametric_min_width_m),
                  static_cast<unsigned long long>(v.parametric_triangles),
                  static_cast<unsigned long long>(v.parametric_clusters),
                  static_cast<unsigned long long>(v.parametric_candidates));
    std::printf("              decode %.2f s, cells %.2f s, embree %.2f s, rays %.2f s\n",
                v.decode_s, v.voxelize_s, v.embree_build_s, v.sampling_s);
  }
  std::printf("  peak memory %.1f MiB\n", double(r.peak_rss_bytes) / (1024.0 * 1024.0));
  std::printf("  package     %llu bytes, %.2f bytes per input triangle\n",
              static_cast<unsigned long long>(r.package_bytes),
              r.input_triangles ? double(r.package_bytes) / double(r.input_triangles) : 0.0);
}


// The options every build takes, on the one-machine command and on `plan`.
void addBuildOptions(CLI::App* cmd, PreprocessArgs& args) {
  cmd->add_option("--memory-budget", args.memory_budget,
                  "Host memory for the build, e.g. 2G or 512M (default 2G)");
  cmd->add_option("--cluster-size", args.cluster_size,
                  "Triangles per cluster, 64-4096 (default 256)");
  cmd->add_option("--parametric-cluster-size", args.parametric_cluster_size,
                  "Parametric instances per cluster, 1-65536 (default 64)");
  cmd->add_option("--brick-triangles", args.brick_triangles,
                  "Most triangles per brick (default: derived from the memory budget)");
  cmd->add_option("--visibility", args.visibility,
                  "View cells and occluder sets: on or off (default on)")
      ->check(CLI::IsMember({"on", "off"}));
  cmd->add_option("--visibility-rays", args.visibility_rays, "Rays per view cell (default 1024)")
      ->check(CLI::Range(1u, 1u << 20));
  cmd->add_option("--view-cell-size", args.view_cell_size_m,
                  "View cell edge in metres (default: chosen from the model's size)")
      ->check(CLI::Range(0.0, 1e6));
  cmd->add_option("--parametric-occluders", args.parametric_occluders,
                  "Parametric clusters as visibility candidates: on or off (default on)")
      ->check(CLI::IsMember({"on", "off"}));
  cmd->add_option("--up", args.up,
                  "The inputs' up axis: y or z (default: y for glTF, z for everything else)")
      ->check(CLI::IsMember({"auto", "y", "z"}));
  cmd->add_option("--cad-primitives", args.cad_primitives,
                  "STEP solids that are cylinders, cones, spheres or boxes stay primitives: on or "
                  "off (mesh everything; default on)")
      ->check(CLI::IsMember({"on", "off"}));
  cmd->add_option("--cad-tolerance", args.cad_tolerance_m,
                  "Chordal tolerance in metres for meshing STEP faces (default: min(2 mm, 0.2 % of "
                  "each part's size))")
      ->check(CLI::Range(1e-7, 1.0));
  cmd->add_option("--cad-bspline", args.cad_bspline,
                  "STEP B-spline faces by the conforming tessellator, or by OpenCASCADE's own "
                  "mesher (a reference to compare against): conforming or brepmesh (default "
                  "conforming)")
      ->check(CLI::IsMember({"conforming", "brepmesh"}));
  cmd->add_option("--exclude-layer", args.exclude_layers,
                  "Leave the objects of this layer out of the package (repeatable)")
      ->allow_extra_args(false);
  cmd->add_option("--db", args.db,
                  "Project database (SQLite) the objects' keys refer to: the package names it, "
                  "so pick, find and view open it without --db")
      ->check(CLI::ExistingFile);
}

PreprocessOptions buildOptions(const PreprocessArgs& args) {
  if (!args.db.empty()) ProjectDatabase::open(args.db);  // a bad database fails before the build
  PreprocessOptions options;
  for (const auto& input : args.inputs) options.inputs.emplace_back(input);
  options.output = args.output;
  options.work_dir = args.work;
  options.memory_budget_bytes = parseByteSize(args.memory_budget, "--memory-budget");
  options.threads = args.threads;
  options.cluster_size = args.cluster_size;
  options.parametric_cluster_size = args.parametric_cluster_size;
  options.max_brick_triangles = args.brick_triangles;
  options.resume = args.resume;
  options.keep_work_dir = args.keep_work;
  options.visibility = args.visibility == "on";
  options.visibility_rays = args.visibility_rays;
  options.view_cell_size_m = args.view_cell_size_m;
  options.parametric_occluders = args.parametric_occluders == "on";
  options.exclude_layers = args.exclude_layers;
  options.up = parseUpAxis(args.up);
  options.cad.primitives = args.cad_primitives == "on";
  options.cad.tolerance_m = args.cad_tolerance_m;
  options.cad.conforming_bspline = args.cad_bspline == "conforming";
  options.database = args.db;
  return options;
}

void printPlan(const PreprocessPlan& plan) {
  uint64_t largest = 0;
  for (const BrickJob& job : plan.jobs) largest = std::max(largest, job.triangles);
  std::printf("plan: %zu brick jobs in %s\n", plan.jobs.size(),
              plan.options.work_dir.string().c_str());
  std::printf("  input       %llu triangles, %llu parametric instances, %llu objects\n",
              static_cast<unsigned long long>(plan.input_triangles),
              static_cast<unsigned long long>(plan.primitives),
              static_cast<unsigned long long>(plan.objects));
  std::printf("  largest     %llu triangles\n", static_cast<unsigned long long>(largest));
  std::printf("  manifest    %s\n", planPath(plan.options.work_dir).string().c_str());
}

void printBrickJob(const BrickJobReport& job, uint32_t count) {
  if (job.already_built) {
    std::printf("brick %u of %u: already built\n", job.index, count);
    return;
  }
  std::printf("brick %u of %u: %llu triangles, %llu clusters, %.2f s, peak %.1f MiB\n", job.index,
              count, static_cast<unsigned long long>(job.triangles),
              static_cast<unsigned long long>(job.clusters), job.seconds,
              double(job.peak_rss_bytes) / (1024.0 * 1024.0));
}

// The project database of a plan without --db: IFC inputs' properties next to the package.
void addIfcDatabase(PreprocessPlan& plan, const std::filesystem::path& output) {
  if (plan.options.database.empty()) plan.options.database = ifcDatabase(plan.options.inputs, output);
}

void registerPlanStep(CLI::App* preprocess, const GlobalOptions& global) {
  auto args = std::make_shared<PreprocessArgs>();
  CLI::App* cmd = preprocess->add_subcommand(
      "plan", "Survey and brick the inputs into a work directory, with a manifest of brick jobs");
  cmd->add_option("inputs", args->inputs, "Scene files")->required()->check(CLI::ExistingFile);
  cmd->add_option("--work", args->work, "The work directory (shared by every step)")->required();
  cmd->add_option("--threads", args->threads, "Worker threads (default: all cores)");
  addBuildOptions(cmd, *args);
  cmd->callback([args, &global] {
    auto progress = makeCommandProgress(global);
    PreprocessOptions options = buildOptions(*args);
    options.progress = progress.get();
    printPlan(planPreprocess(options));
  });
}

void registerBrickStep(CLI::App* preprocess, const GlobalOptions& global) {
  struct BrickArgs {
    std::string work;
    std::optional<uint32_t> index, job;
    uint32_t threads = 0;
  };
  auto args = std::make_shared<BrickArgs>();
  CLI::App* cmd = preprocess->add_subcommand(
      "brick", "Build one brick of a plan (a no-op when it is built already)");
  cmd->add_option("--work", args->work, "The plan's work directory")->required();
  auto* index = cmd->add_option("--index", args->index, "The brick's number");
  cmd->add_option("--job", args->job,
                  "The brick by its place in the plan's largest-first order (a job array's task "
                  "id)")
      ->excludes(index);
  cmd->add_option("--threads", args->threads, "Worker threads (default: all cores)");
  cmd->callback([args, &global] {
    if (!args->index && !args->job)
      throw CLI::ValidationError("preprocess brick", "--index or --job names the brick");
    const PreprocessPlan plan = readPreprocessPlan(args->work);
    uint32_t brick = args->index.value_or(0);
    if (args->job) {
      if (*args->job >= plan.jobs.size())
        throw std::invalid_argument("preprocess brick: --job " + std::to_string(*args->job) +
                                    " is not in the plan (" + std::to_string(plan.jobs.size()) +
                                    " jobs)");
      brick = plan.jobs[*args->job].index;
    }
    auto progress = makeCommandProgress(global);
    StepOptions step;
    step.threads = args->threads;
    step.progress = progress.get();
    PlannedBricks bricks(plan, step);
    printBrickJob(bricks.build(brick), bricks.count());
  });
}

void registerMergeStep(CLI::App* preprocess, const GlobalOptions& global) {
  struct MergeArgs {
    std::string work, output;
    uint32_t threads = 0;
    bool keep_work = false;
  };
  auto args = std::make_shared<MergeArgs>();
  CLI::App* cmd = preprocess->add_subcommand(
      "merge", "Merge a plan's built bricks into the package (and its visibility)");
  cmd->add_option("--work", args->work, "The plan's work directory")->required();
  cmd->add_option("-o,--output", args->output, "Package to write (.twk)")->required();
  cmd->add_option("--threads", args->threads, "Worker threads (default: all cores)");
  cmd->add_flag("--keep-work", args->keep_work, "Keep the work directory after the merge");
  cmd->callback([args, &global] {
    PreprocessPlan plan = readPreprocessPlan(args->work);
    addIfcDatabase(plan, args->output);
    auto progress = makeCommandProgress(global);
    StepOptions step;
    step.threads = args->threads;
    step.progress = progress.get();
    step.output = args->output;
    step.keep_work_dir = args->keep_work;
    printSummary(mergePreprocess(plan, step), args->output);
  });
}

}  // namespace

void registerPreprocessCommand(CLI::App& app, const GlobalOptions& global) {
  auto args = std::make_shared<PreprocessArgs>();
  CLI::App* cmd = app.add_subcommand(
      "preprocess",
      "Build a walkable package from scene files (or one step of the build: plan, brick, merge)");
  cmd->add_option("inputs", args->inputs,
                  "Scene files (.tws, .ply, .obj, .stl, .gltf, .glb, .stp, .step, .ifc)")
      ->check(CLI::ExistingFile);
  CLI::Option* output = cmd->add_option("-o,--output", args->output, "Package to write (.twk)");
  cmd->add_option("--threads", args->threads, "Worker threads (default: all cores)");
  cmd->add_flag("--resume", args->resume,
                "Continue a killed run with the same arguments from its finished bricks");
  cmd->add_flag("--keep-work", args->keep_work, "Keep the work directory");
  cmd->add_option("--work", args->work, "The work directory (default: <output>.work)");
  cmd->add_flag("--mpi", args->mpi,
                "Run under mpirun: rank 0 plans and merges, every rank builds bricks, largest "
                "first, over a work directory all ranks share (a re-run finishes a killed one)");
  addBuildOptions(cmd, *args);
  registerPlanStep(cmd, global);
  registerBrickStep(cmd, global);
  registerMergeStep(cmd, global);
  cmd->callback([cmd, output, args, &global] {
    if (!cmd->get_subcommands().empty()) return;  // a step ran
    if (args->inputs.empty())
      throw CLI::ValidationError("preprocess", "no input files (or a step: plan, brick, merge)");
    if (output->count() == 0)
      throw CLI::ValidationError("preprocess", "-o names the package to write");
    auto progress = makeCommandProgress(global);
    PreprocessOptions options = buildOptions(*args);
    options.progress = progress.get();
    if (args->mpi) {
      MpiPreprocessHooks hooks;
      hooks.before_merge = [&](PreprocessPlan& plan) { addIfcDatabase(plan, options.output); };
      hooks.report = [&](const PreprocessReport& report) { printSummary(report, args->output); };
      hooks.brick = [](const BrickJobReport& job, uint32_t count, int rank) {
        std::printf("rank %d: ", rank);
        printBrickJob(job, count);
        std::fflush(stdout);
      };
      if (const int status = runPreprocessOverMpi(options, hooks); status != 0) std::exit(status);
      return;
    }
    if (options.database.empty()) options.database = ifcDatabase(options.inputs, options.output);
    PreprocessReport report = runPreprocess(options);
    printSummary(report, args->output);
  });
}

}  // namespace tw

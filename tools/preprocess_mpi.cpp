// The split preprocessor over Open MPI; see preprocess_mpi.h.
#include "preprocess_mpi.h"

#include <mpi.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <exception>
#include <memory>
#include <mutex>
#include <optional>
#include <thread>

#include "brick_cache.h"

namespace tw {
namespace {

constexpr int kTagAsk = 1;    // a rank to rank 0: the status of its last brick, and "next?"
constexpr int kTagBrick = 2;  // rank 0's answer: a brick number, or kNoBrick
constexpr int kNoBrick = -1;

// Open MPI's blocking calls poll without sleeping: a rank waiting in one would take a core from
// the ranks building bricks beside it (and from rank 0's plan and merge). Every wait here tests
// and sleeps instead; a brick takes seconds, so the milliseconds do not count.
void waitQuietly(MPI_Request& request, MPI_Status* status = MPI_STATUS_IGNORE) {
  for (int done = 0;;) {
    MPI_Test(&request, &done, status);
    if (done) return;
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
}

// Rank 0's status to every rank (a collective every rank calls).
int shareStatus(int status) {
  MPI_Request request;
  MPI_Ibcast(&status, 1, MPI_INT, 0, MPI_COMM_WORLD, &request);
  waitQuietly(request);
  return status;
}

class MpiSession {
 public:
  MpiSession() {
    MPI_Init_thread(nullptr, nullptr, MPI_THREAD_SERIALIZED, &threading_);
    MPI_Comm_rank(MPI_COMM_WORLD, &rank_);
    MPI_Comm_size(MPI_COMM_WORLD, &size_);
  }
  ~MpiSession() { MPI_Finalize(); }
  MpiSession(const MpiSession&) = delete;
  MpiSession& operator=(const MpiSession&) = delete;

  int rank() const { return rank_; }
  int size() const { return size_; }
  // Rank 0 answers the others on a thread of its own while it builds bricks too.
  bool threadsMayCallMpi() const { return threading_ >= MPI_THREAD_SERIALIZED; }

  // The node's cores shared among the ranks on it.
  uint32_t coresPerRank() const {
    MPI_Comm node;
    MPI_Comm_split_type(MPI_COMM_WORLD, MPI_COMM_TYPE_SHARED, 0, MPI_INFO_NULL, &node);
    int local = 1;
    MPI_Comm_size(node, &local);
    MPI_Comm_free(&node);
    return std::max(1u, std::thread::hardware_concurrency() / uint32_t(std::max(local, 1)));
  }

 private:
  int threading_ = MPI_THREAD_SINGLE;
  int rank_ = 0, size_ = 1;
};

void reportError(int rank, const char* what) {
  std::fprintf(stderr, "terawalk: rank %d: %s\n", rank, what);
  std::fflush(stderr);
}

// Rank 0's queue of the plan's bricks, largest first, shared by its own builder and its answers
// to the other ranks. After a failure it hands out nothing more.
class BrickDispatcher {
 public:
  explicit BrickDispatcher(const std::vector<BrickJob>& jobs) : jobs_(jobs) {}

  std::optional<uint32_t> next() {
    std::lock_guard lock(mutex_);
    if (failed_ || next_ >= jobs_.size()) return std::nullopt;
    return jobs_[next_++].index;
  }
  void fail() {
    std::lock_guard lock(mutex_);
    failed_ = true;
  }
  bool failed() const {
    std::lock_guard lock(mutex_);
    return failed_;
  }

  // Answers every other rank until each has been told there is nothing left.
  void serve(int other_ranks) {
    for (int stopped = 0; stopped < other_ranks;) {
      int status = 0;
      MPI_Request request;
      MPI_Status source;
      MPI_Irecv(&status, 1, MPI_INT, MPI_ANY_SOURCE, kTagAsk, MPI_COMM_WORLD, &request);
      waitQuietly(request, &source);
      if (status != 0) fail();
      const std::optional<uint32_t> brick = next();
      int answer = brick ? int(*brick) : kNoBrick;
      MPI_Send(&answer, 1, MPI_INT, source.MPI_SOURCE, kTagBrick, MPI_COMM_WORLD);
      if (!brick) ++stopped;
    }
  }

 private:
  const std::vector<BrickJob>& jobs_;
  mutable std::mutex mutex_;
  size_t next_ = 0;
  bool failed_ = false;
};

// This rank's brick builder: the plan's bricking and seams, read once.
class RankBuilder {
 public:
  RankBuilder(int rank, const PreprocessOptions& options, uint32_t threads,
              const MpiPreprocessHooks& hooks)
      : rank_(rank), hooks_(hooks) {
    try {
      const std::filesystem::path work =
          options.work_dir.empty() ? workDirFor(options.output) : options.work_dir;
      const PreprocessPlan plan = readPreprocessPlan(work);
      StepOptions step;
      step.threads = threads;
      bricks_ = std::make_unique<PlannedBricks>(plan, step);
    } catch (const std::exception& e) {
      reportError(rank_, e.what());
    }
  }
  bool ready() const { return bricks_ != nullptr; }

  bool build(uint32_t brick) {
    std::printf("rank %d (pid %d): brick %u of %u started\n", rank_, int(::getpid()), brick,
                bricks_->count());
    std::fflush(stdout);
    try {
      const BrickJobReport job = bricks_->build(brick);
      if (hooks_.brick) hooks_.brick(job, bricks_->count(), rank_);
      return true;
    } catch (const std::exception& e) {
      reportError(rank_, ("brick " + std::to_string(brick) + ": " + e.what()).c_str());
      return false;
    }
  }
  void release() { bricks_.reset(); }

 private:
  int rank_;
  const MpiPreprocessHooks& hooks_;
  std::unique_ptr<PlannedBricks> bricks_;
};

// Rank 0: plans, builds bricks while a thread answers the others, merges.
int runRankZero(const MpiSession& mpi, const PreprocessOptions& options,
                const MpiPreprocessHooks& hooks) {
  std::optional<PreprocessPlan> plan;
  try {
    plan = planPreprocess(options);
    std::printf("rank 0: plan of %zu bricks; %d ranks build them\n", plan->jobs.size(), mpi.size());
    std::fflush(stdout);
  } catch (const std::exception& e) {
    reportError(0, e.what());
  }
  if (shareStatus(plan ? 0 : 1) != 0) return 1;

  const uint32_t threads = options.threads ? options.threads : mpi.coresPerRank();
  RankBuilder builder(0, options, threads, hooks);
  BrickDispatcher dispatcher(plan->jobs);
  if (!builder.ready()) dispatcher.fail();
  const bool own_bricks = mpi.size() == 1 || mpi.threadsMayCallMpi();
  std::thread answers;
  if (mpi.size() > 1) {
    if (own_bricks)
      answers = std::thread([&] { dispatcher.serve(mpi.size() - 1); });
    else
      dispatcher.serve(mpi.size() - 1);
  }
  if (own_bricks)
    while (const std::optional<uint32_t> brick = dispatcher.next())
      if (!builder.build(*brick)) dispatcher.fail();
  if (answers.joinable()) answers.join();
  builder.release();

  int status = dispatcher.failed() ? 1 : 0;
  if (status == 0) {
    try {
      PreprocessPlan merged = *plan;
      if (hooks.before_merge) hooks.before_merge(merged);
      StepOptions step;
      step.threads = options.threads;
      step.progress = options.progress;
      step.output = options.output;
      step.keep_work_dir = options.keep_work_dir;
      const PreprocessReport report = mergePreprocess(merged, step);
      if (hooks.report) hooks.report(report);
    } catch (const std::exception& e) {
      reportError(0, e.what());
      status = 1;
    }
  } else {
    reportError(0, "bricks failed: the finished ones stay in the work directory; run the same "
                   "command again to build the rest and merge");
  }
  return shareStatus(status);
}

// Every other rank: asks rank 0 for bricks until it says there are none left.
int runOtherRank(const MpiSession& mpi, const PreprocessOptions& options,
                 const MpiPreprocessHooks& hooks) {
  if (shareStatus(0) != 0) return 1;  // the plan failed
  const uint32_t threads = options.threads ? options.threads : mpi.coresPerRank();
  RankBuilder builder(mpi.rank(), options, threads, hooks);
  int status = builder.ready() ? 0 : 1;
  for (;;) {
    MPI_Send(&status, 1, MPI_INT, 0, kTagAsk, MPI_COMM_WORLD);
    int brick = kNoBrick;
    MPI_Request request;
    MPI_Irecv(&brick, 1, MPI_INT, 0, kTagBrick, MPI_COMM_WORLD, &request);
    waitQuietly(request);
    if (brick == kNoBrick) break;
    status = builder.build(uint32_t(brick)) ? 0 : 1;
  }
  builder.release();
  return shareStatus(0);  // rank 0's merge
}

}  // namespace

bool haveMpi() { return true; }

int runPreprocessOverMpi(const PreprocessOptions& options, const MpiPreprocessHooks& hooks) {
  MpiSession mpi;
  return mpi.rank() == 0 ? runRankZero(mpi, options, hooks) : runOtherRank(mpi, options, hooks);
}

}  // namespace tw

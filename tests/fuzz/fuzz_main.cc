// scanreg-fuzz: an in-tree mutation fuzzer for every reader (issue 16). Each execution takes a
// seed of the target's format, applies 1-5 mutations (bit flips, interesting bytes, deleted,
// inserted, duplicated or spliced ranges, truncation, numbers replaced by extreme ones), writes the
// input and reads it. A crash or hang kills the process with the input left at the printed path;
// a reader that breaks its promises (fuzz_targets.h) or throws is reported with the input kept.
//
//   scanreg-fuzz [--target NAME ...] [--seconds S | --execs N] [--seed K] [--work DIR]
//
// Under ASan + UBSan (cmake -DSCANREG_SANITIZE=ON) run with
//   ASAN_OPTIONS=max_allocation_size_mb=2048:allocator_may_return_null=0
// so that any allocation beyond 2 GB is reported as a failure; otherwise the data segment is
// limited to 2 GB (setrlimit) and an allocation beyond it surfaces as std::bad_alloc. Put --work on
// a tmpfs (/dev/shm): each input is written and read back, and a disk makes that ~40x slower.
#include <sys/resource.h>
#include <unistd.h>

#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <random>
#include <set>
#include <string>

#include "core/common/log.h"
#include "tests/fuzz/fuzz_targets.h"

namespace scanreg::fuzz {
namespace {

namespace fs = std::filesystem;

const char* const kNastyNumbers[] = {"0",   "-1",         "1e309",       "-1e309",      "nan",        "inf",
                                     "1e-320", "2147483647", "2147483648", "4294967296", "1073741824", "-2147483649",
                                     "18446744073709551616", "65536", "3", "1.5", "0x10", "1e30"};
const unsigned char kInterestingBytes[] = {0x00, 0xff, 0x7f, 0x80, '\n', '\r', ' ', '-', '9', '"', '{', '}', ',', 0x1b};

class Mutator {
 public:
  explicit Mutator(unsigned seed) : rng_(seed) {}

  std::string Mutate(std::string data, const std::vector<std::string>& corpus, std::size_t max_size) {
    const int n = 1 + Pick(5);
    for (int k = 0; k < n; ++k) {
      switch (Pick(8)) {
        case 0:  // bit flip
          if (!data.empty()) data[Pick(data.size())] ^= char(1u << Pick(8));
          break;
        case 1:  // an interesting byte
          if (!data.empty()) data[Pick(data.size())] = char(kInterestingBytes[Pick(sizeof kInterestingBytes)]);
          break;
        case 2: {  // delete a range
          if (data.empty()) break;
          const std::size_t at = Pick(data.size());
          data.erase(at, 1 + Pick(std::min<std::size_t>(64, data.size() - at)));
          break;
        }
        case 3: {  // insert random bytes or duplicate a range
          const std::size_t at = Pick(data.size() + 1);
          std::string piece;
          if (!data.empty() && Pick(2)) {
            const std::size_t from = Pick(data.size());
            piece = data.substr(from, 1 + Pick(std::min<std::size_t>(256, data.size() - from)));
          } else {
            for (std::size_t i = 0, len = 1 + Pick(32); i < len; ++i) piece += char(Pick(256));
          }
          data.insert(at, piece);
          break;
        }
        case 4:  // truncate
          data.resize(Pick(data.size() + 1));
          break;
        case 5:
        case 6: {  // a number replaced by an extreme one
          const std::size_t start = Pick(data.size() + 1);
          std::size_t a = data.find_first_of("0123456789", start);
          if (a == std::string::npos) break;
          std::size_t b = a;
          while (b < data.size() && (std::isdigit(static_cast<unsigned char>(data[b])) || data[b] == '.' || data[b] == 'e'))
            ++b;
          if (a > 0 && data[a - 1] == '-') --a;
          data.replace(a, b - a, kNastyNumbers[Pick(sizeof kNastyNumbers / sizeof *kNastyNumbers)]);
          break;
        }
        case 7: {  // splice with another seed of the same format
          const std::string& other = corpus[Pick(corpus.size())];
          const std::size_t cut = Pick(data.size() + 1), from = Pick(other.size() + 1);
          data = data.substr(0, cut) + other.substr(from);
          break;
        }
      }
      if (data.size() > max_size) data.resize(max_size);
    }
    return data;
  }

 private:
  std::size_t Pick(std::size_t n) { return n == 0 ? 0 : std::uniform_int_distribution<std::size_t>(0, n - 1)(rng_); }
  std::mt19937_64 rng_;
};

const char* g_current = nullptr;  // the input being read, for the crash message
void OnFatalSignal(int sig) {
  const char msg[] = "\nscanreg-fuzz: the reader died on the input at ";
  (void)!write(2, msg, sizeof msg - 1);
  if (g_current) (void)!write(2, g_current, std::strlen(g_current));
  (void)!write(2, "\n", 1);
  std::signal(sig, SIG_DFL);
  std::raise(sig);
}

struct Tally {
  long execs = 0, accepted = 0, rejected = 0, failures = 0;
  double seconds = 0.0;
};

int Main(int argc, char** argv) {
  std::set<std::string> only;
  double seconds = 10.0;
  long execs = 0;
  unsigned seed = 1;
  fs::path work = fs::temp_directory_path() / ("scanreg-fuzz-" + std::to_string(getpid()));
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= argc) throw std::invalid_argument(a + " needs a value");
      return argv[++i];
    };
    if (a == "--target") only.insert(value());
    else if (a == "--seconds") seconds = std::stod(value());
    else if (a == "--execs") execs = std::stol(value());
    else if (a == "--seed") seed = unsigned(std::stoul(value()));
    else if (a == "--work") work = value();
    else throw std::invalid_argument("unknown option " + a + " (see the comment at the top of fuzz_main.cc)");
  }
#if !defined(__SANITIZE_ADDRESS__)
  const rlimit data{rlim_t(2) << 30, rlim_t(2) << 30};
  setrlimit(RLIMIT_DATA, &data);
#endif
  // Warnings about skipped lines are expected by the thousand; a raw control byte in one is not.
  long raw_control_bytes = 0;
  SetLogHandler([&](LogLevel, const std::string& message) {
    for (unsigned char ch : message) raw_control_bytes += ch < 0x20 || ch == 0x7f;
  });
  std::vector<FuzzTarget> targets = MakeTargets(work);
  for (int sig : {SIGSEGV, SIGABRT, SIGBUS, SIGFPE, SIGILL, SIGALRM}) std::signal(sig, OnFatalSignal);
  int failures = 0;
  std::printf("%-14s %10s %10s %10s %9s %8s\n", "target", "execs", "accepted", "rejected", "failures", "seconds");
  for (const FuzzTarget& t : targets) {
    if (!only.empty() && !only.count(t.name)) continue;
    Mutator mutator(seed);
    std::size_t largest = 0;
    for (const std::string& s : t.seeds) largest = std::max(largest, s.size());
    const std::string input = (work / ("input-" + t.name + t.extension)).string();
    g_current = input.c_str();
    Tally tally;
    const auto t0 = std::chrono::steady_clock::now();
    auto elapsed = [&] { return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(); };
    for (long k = 0; execs > 0 ? k < execs : elapsed() < seconds; ++k) {
      // The seeds themselves first (they must be accepted), then mutants.
      const bool is_seed = k < long(t.seeds.size());
      const std::string data =
          is_seed ? t.seeds[k] : mutator.Mutate(t.seeds[k % t.seeds.size()], t.seeds, 4 * largest + 4096);
      {
        std::ofstream out(input, std::ios::binary | std::ios::trunc);
        out.write(data.data(), std::streamsize(data.size()));
      }
      alarm(20);  // a read of a few kilobytes that takes longer hangs
      std::string broken;
      bool accepted = false;
      try {
        broken = t.read(input, &accepted);
      } catch (const std::exception& e) {
        broken = std::string("uncaught exception: ") + e.what();
      }
      alarm(0);
      if (raw_control_bytes > 0 && broken.empty()) broken = "a log message with a raw control byte";
      raw_control_bytes = 0;
      ++tally.execs;
      (accepted ? tally.accepted : tally.rejected) += 1;
      if (is_seed && !accepted) broken = "the seed itself is rejected";
      if (!broken.empty()) {
        ++tally.failures;
        if (tally.failures <= 5) {  // the first few, each with its input kept
          const fs::path kept = work / ("failure-" + t.name + "-" + std::to_string(tally.failures) + t.extension);
          fs::copy_file(input, kept, fs::copy_options::overwrite_existing);
          std::fprintf(stderr, "%s: %s (input kept: %s)\n", t.name.c_str(), broken.substr(0, 300).c_str(),
                       kept.c_str());
        }
      }
    }
    tally.seconds = elapsed();
    std::printf("%-14s %10ld %10ld %10ld %9ld %8.1f\n", t.name.c_str(), tally.execs, tally.accepted, tally.rejected,
                tally.failures, tally.seconds);
    std::fflush(stdout);
    // A harness that never reaches the reader's parsing, or whose mutants are all rejected, proves nothing.
    if (tally.accepted <= long(t.seeds.size()) || tally.rejected == 0) {
      std::fprintf(stderr, "%s: the mutants were %ld accepted / %ld rejected: the harness does not exercise the reader\n",
                   t.name.c_str(), tally.accepted, tally.rejected);
      ++failures;
    }
    failures += int(tally.failures);
  }
  g_current = nullptr;
  if (failures == 0) fs::remove_all(work);
  return failures == 0 ? 0 : 1;
}

}  // namespace
}  // namespace scanreg::fuzz

int main(int argc, char** argv) {
  try {
    return scanreg::fuzz::Main(argc, argv);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "scanreg-fuzz: %s\n", e.what());
    return 2;
  }
}

// Atomic outputs (issue 10): prt-import killed with SIGKILL at any moment, during reading, cleaning
// or in the middle of writing its output, leaves the previous pool at the output path intact (it
// still opens with PoolFile, byte for byte the same) and no partial file there. The only trace a
// killed run leaves is its own temporary file, PATH.tmp.HOST.PID (PoolWriter, formats/POOL.md
// "Writing"); the next successful write of PATH removes it, because HOST is this host and PID is
// dead, and never the temporary file of a live writer, of another host or of another PATH.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <spawn.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <chrono>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <thread>
#include <vector>

#include "prt/formats/pool.h"

extern char** environ;

namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

/// Points of the large input: 3M points with normals is a 72 MB PLY and a 72 MB pool, so that the
/// write (with its fsync) takes long enough on a disk to be hit in its middle.
constexpr std::uint32_t k_points = 3'000'000;

std::string slurp(const fs::path& p) {
    std::ifstream in(p, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

/// A binary little-endian PLY with float x y z nx ny nz (normals present: no PCA, the run is
/// reading, cleaning and writing). Positions from a fixed LCG, so no two points coincide.
void write_ply(const fs::path& path, std::uint32_t n, float offset) {
    std::ofstream out(path, std::ios::binary);
    out << "ply\nformat binary_little_endian 1.0\nelement vertex " << n
        << "\nproperty float x\nproperty float y\nproperty float z\nproperty float nx\nproperty float ny\n"
           "property float nz\nend_header\n";
    std::vector<float> row(6 * 65536);
    std::uint64_t state = 12345;
    for (std::uint32_t done = 0; done < n;) {
        const std::uint32_t chunk = std::min<std::uint32_t>(65536, n - done);
        for (std::uint32_t i = 0; i < chunk; ++i) {
            for (int a = 0; a < 3; ++a) {
                state = state * 6364136223846793005ull + 1442695040888963407ull;
                row[6 * i + a] = offset + static_cast<float>(state >> 40) / static_cast<float>(1u << 24);
            }
            row[6 * i + 3] = 0.f;
            row[6 * i + 4] = 0.f;
            row[6 * i + 5] = 1.f;
        }
        out.write(reinterpret_cast<const char*>(row.data()),
                  static_cast<std::streamsize>(chunk * 6 * sizeof(float)));
        done += chunk;
    }
}

class AtomicWriteTest : public ::testing::Test {
protected:
    void SetUp() override {
        m_tool = fs::path(PRT_BIN_DIR) / "prt-import";
        if (!fs::exists(m_tool)) GTEST_SKIP() << "prt-import is not built in " << PRT_BIN_DIR;
        // On disk (not tmpfs): fsync has real work to do, as for a user's output.
        m_dir = fs::path(PRT_BIN_DIR).parent_path() / ("atomic_write_test." + std::to_string(::getpid()));
        fs::remove_all(m_dir);
        fs::create_directories(m_dir);
    }
    void TearDown() override {
        if (!m_dir.empty()) fs::remove_all(m_dir);
    }

    /// Starts prt-import INPUT -o OUTPUT --quiet; returns its pid.
    pid_t start(const fs::path& input, const fs::path& output) {
        std::vector<std::string> args{m_tool.string(), input.string(), "-o", output.string(), "--quiet"};
        std::vector<char*> argv;
        for (std::string& a : args) argv.push_back(a.data());
        argv.push_back(nullptr);
        posix_spawn_file_actions_t actions;
        posix_spawn_file_actions_init(&actions);
        posix_spawn_file_actions_addopen(&actions, 1, "/dev/null", O_WRONLY, 0);
        posix_spawn_file_actions_addopen(&actions, 2, (m_dir / "stderr.txt").c_str(),
                                         O_WRONLY | O_CREAT | O_TRUNC, 0644);
        pid_t pid = -1;
        const int rc = posix_spawn(&pid, argv[0], &actions, nullptr, argv.data(), environ);
        posix_spawn_file_actions_destroy(&actions);
        EXPECT_EQ(rc, 0) << std::strerror(rc);
        return pid;
    }

    /// Waits for a child; returns its exit status, or 128 + signal.
    static int finish(pid_t pid) {
        int status = 0;
        while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
        }
        return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
    }

    fs::path m_tool;
    fs::path m_dir;
};

/// HOST of the temporary names as formats/POOL.md defines it: gethostname() with every character
/// other than A-Z a-z 0-9 - _ replaced by '_' ("localhost" when there is no name).
std::string host_tag() {
    char name[256] = {};
    if (::gethostname(name, sizeof name - 1) != 0 || name[0] == '\0') return "localhost";
    std::string tag(name);
    std::replace_if(
        tag.begin(), tag.end(), [](unsigned char c) { return !std::isalnum(c) && c != '-' && c != '_'; },
        '_');
    return tag;
}

/// The temporary file a writer with this pid uses for `path`.
fs::path temporary_of(const fs::path& path, pid_t pid) {
    return path.string() + ".tmp." + host_tag() + "." + std::to_string(pid);
}

/// Names in `dir` that start with `prefix`, sorted.
std::vector<std::string> names_with(const fs::path& dir, const std::string& prefix) {
    std::vector<std::string> out;
    for (const auto& e : fs::directory_iterator(dir)) {
        const std::string name = e.path().filename().string();
        if (name.rfind(prefix, 0) == 0) out.push_back(name);
    }
    std::sort(out.begin(), out.end());
    return out;
}

/// Size of a file, or -1 when it does not exist.
std::int64_t size_of(const fs::path& p) {
    struct stat st {};
    return ::stat(p.c_str(), &st) == 0 ? static_cast<std::int64_t>(st.st_size) : -1;
}

TEST_F(AtomicWriteTest, KilledImportLeavesThePreviousPoolIntact) {
    const fs::path small = m_dir / "small.ply";
    const fs::path big = m_dir / "big.ply";
    const fs::path out = m_dir / "out.pool";
    write_ply(small, 1000, 100.f);
    write_ply(big, k_points, 0.f);

    // The previous pool, and how long a full import of the large input takes here.
    ASSERT_EQ(finish(start(small, out)), 0) << slurp(m_dir / "stderr.txt");
    const std::string previous = slurp(out);
    ASSERT_EQ(prt::pool::PoolFile::open(out).model_info().point_count, 1000u);
    const auto t0 = Clock::now();
    ASSERT_EQ(finish(start(big, m_dir / "calibration.pool")), 0) << slurp(m_dir / "stderr.txt");
    const double full_seconds = std::chrono::duration<double>(Clock::now() - t0).count();
    const std::int64_t full_size = size_of(m_dir / "calibration.pool");
    fs::remove(m_dir / "calibration.pool");
    ASSERT_GT(full_size, 0);

    // Kill moments: fractions of a full run (reading, cleaning, writing), then the write itself:
    // as soon as the temporary file appears, and once it holds half of the pool.
    struct Moment {
        const char* name;
        double fraction;         // of full_seconds; < 0: watch the temporary file instead
        std::int64_t tmp_bytes;  // with fraction < 0: kill once the temporary file has this many
    };
    const Moment moments[] = {
        {"10% of a run", 0.1, 0},          {"40% of a run", 0.4, 0},
        {"70% of a run", 0.7, 0},          {"90% of a run", 0.9, 0},
        {"temporary file created", -1, 0}, {"temporary file half written", -1, full_size / 2}};
    std::vector<std::string> stale;  // temporary files of killed runs (a later run may remove them)
    std::string current = previous;  // what out.pool must hold: the last complete pool
    int killed_mid_write = 0;        // killed with its temporary file there, out.pool untouched
    int finished_before_kill = 0;    // the rename came first: out.pool is the new, complete pool
    for (const Moment& m : moments) {
        SCOPED_TRACE(m.name);
        const pid_t pid = start(big, out);
        const fs::path tmp = temporary_of(out, pid);
        const auto begin = Clock::now();
        if (m.fraction >= 0) {
            std::this_thread::sleep_for(std::chrono::duration<double>(m.fraction * full_seconds));
        } else {
            // Poll every 0.2 ms until the temporary file is there with enough bytes.
            const auto ready = [&] {
                const std::int64_t s = size_of(tmp);
                return s >= 0 && s >= m.tmp_bytes;
            };
            while (!ready()) {
                if (::waitpid(pid, nullptr, WNOHANG) == pid) FAIL() << "finished before the moment";
                if (Clock::now() - begin > std::chrono::duration<double>(10 * full_seconds + 10))
                    FAIL() << "the temporary file never appeared";
                std::this_thread::sleep_for(std::chrono::microseconds(200));
            }
        }
        const std::int64_t tmp_at_kill = size_of(tmp);
        ::kill(pid, SIGKILL);
        const int status = finish(pid);

        // out.pool is always a complete pool: the previous one byte for byte, or (when the kill
        // came after the rename) the new one, whole.
        const std::string now = slurp(out);
        if (now == current) {
            EXPECT_EQ(status, 128 + SIGKILL);
            if (tmp_at_kill >= 0) ++killed_mid_write;
        } else {
            ++finished_before_kill;
            EXPECT_EQ(static_cast<std::int64_t>(now.size()), full_size)
                << "out.pool is neither the old nor a whole new pool";
            current = now;
        }
        EXPECT_NO_THROW((void)prt::pool::PoolFile::open(out));
        // Nothing else appeared but this run's temporary file (earlier killed runs' files are there
        // too unless a run finished, which removes them).
        for (const auto& e : fs::directory_iterator(m_dir)) {
            const std::string name = e.path().filename().string();
            if (name == "small.ply" || name == "big.ply" || name == "out.pool" || name == "stderr.txt")
                continue;
            if (name == tmp.filename().string()) {
                if (std::find(stale.begin(), stale.end(), name) == stale.end()) stale.push_back(name);
                continue;
            }
            if (std::find(stale.begin(), stale.end(), name) != stale.end()) continue;
            ADD_FAILURE() << "unexpected file " << name;
        }
    }
    // The dangerous window was really hit: at least one run (the one killed as soon as its
    // temporary file appeared) died between creating and renaming its output.
    EXPECT_GE(killed_mid_write, 1);
    std::cout << "[ note ] " << killed_mid_write << " runs killed while their output was being written, "
              << finished_before_kill << " finished before the signal arrived\n";

    // A later successful run replaces the pool and removes the killed runs' temporary files (their
    // PIDs are dead: each was reaped above) along with leaving none of its own.
    const std::vector<std::string> before = names_with(m_dir, "out.pool.tmp.");
    std::uint64_t before_bytes = 0;
    for (const std::string& name : before) before_bytes += fs::file_size(m_dir / name);
    EXPECT_GE(before.size(), 1u) << "the run killed as its temporary file appeared left no file";
    const pid_t pid = start(big, out);
    ASSERT_EQ(finish(pid), 0) << slurp(m_dir / "stderr.txt");
    EXPECT_EQ(prt::pool::PoolFile::open(out).model_info().point_count, k_points);
    EXPECT_EQ(names_with(m_dir, "out.pool.tmp."), std::vector<std::string>{})
        << "stale temporary files of dead writers must be gone after a successful write";
    std::cout << "[ note ] full import " << full_seconds << " s, pool " << full_size << " bytes; "
              << before.size() << " stale temporary files of killed runs (" << before_bytes
              << " bytes) removed by the next successful write\n";
}

TEST_F(AtomicWriteTest, CleanupSparesLiveWritersOtherHostsAndOtherOutputs) {
    const fs::path small = m_dir / "small.ply";
    const fs::path out = m_dir / "out.pool";
    write_ply(small, 1000, 100.f);
    // A dead PID (a child that exited and was reaped) and a live one (a child waiting to be killed).
    const pid_t dead = ::fork();
    ASSERT_GE(dead, 0);
    if (dead == 0) ::_exit(0);
    ASSERT_EQ(finish(dead), 0);
    const pid_t live = ::fork();
    ASSERT_GE(live, 0);
    if (live == 0) {
        ::pause();
        ::_exit(0);
    }
    ASSERT_EQ(::kill(dead, 0), -1) << "pid " << dead << " was reused at once";
    ASSERT_EQ(errno, ESRCH);

    const std::string tag = host_tag();
    const std::string d = std::to_string(dead);
    const std::vector<std::string> removed{"out.pool.tmp." + tag + "." + d};
    std::vector<std::string> kept{
        "out.pool.tmp." + tag + "." + std::to_string(live),        // a live writer
        "out.pool.tmp." + tag + "." + std::to_string(::getpid()),  // this test, also alive
        "out.pool.tmp.other-host-" + tag + "." + d,                // another host on a shared folder
        "other.pool.tmp." + tag + "." + d,                         // another output's temporary file
        "out.pool.tmp." + tag + "." + d + "x",                     // not a writer's name
        "out.pool.tmp." + tag + ".0" + d,
        "out.pool.tmp." + d,  // the name before HOST was added: whose it was is unknown
    };
    for (const std::string& name : removed) std::ofstream(m_dir / name) << "partial";
    for (const std::string& name : kept) std::ofstream(m_dir / name) << "partial";

    const int status = finish(start(small, out));
    ::kill(live, SIGKILL);
    finish(live);
    ASSERT_EQ(status, 0) << slurp(m_dir / "stderr.txt");
    EXPECT_EQ(prt::pool::PoolFile::open(out).model_info().point_count, 1000u);
    for (const std::string& name : removed) EXPECT_FALSE(fs::exists(m_dir / name)) << name;
    for (const std::string& name : kept) EXPECT_TRUE(fs::exists(m_dir / name)) << name;
}

}  // namespace

// Logger benchmark (DESIGN.md §8): sustained real-time logging of 3 tracked
// devices at 1 kHz plus 90 Hz frame records, then unpaced throughput of the
// SampleWriter against a raw prepared-statement SQLite loop writing the same
// rows, both measured in this run on the same disk. Frame records carry eye
// geometry as the session fills it: the same every frame (headless, desktop;
// stored once), changing every frame (an OpenXR runtime's worst case), or none.
//   bench_logger_throughput [--seconds S] [--dir DIR] [--rows N] [--views same|changing|none]
#include "curvlab/harness/data/sample_writer.hpp"
#include "curvlab/harness/data/session_store.hpp"

#include <sqlite3.h>

#include <chrono>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <string>
#include <thread>

using namespace curvlab::harness::data;
using Clock = std::chrono::steady_clock;

namespace {

double process_cpu_s() {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + static_cast<double>(ts.tv_nsec) * 1e-9;
}

TrackingSample sample(std::int64_t session, std::int64_t i) {
  TrackingSample s;
  s.session_id = session;
  s.trial_id = -1;
  s.frame_index = i / 33;
  s.t_ns = i * 333'333;
  s.device = static_cast<TrackedDevice>(i % 3);
  s.position_valid = s.orientation_valid = true;
  s.lab_position_m = {0.001 * static_cast<double>(i % 100), 1.6, -0.3};
  s.has_virtual_pose = true;
  for (int k = 0; k < 16; ++k) s.virtual_pose[static_cast<std::size_t>(k)] = k % 5 == 0 ? 1.0 : 0.0;
  s.has_state = true;
  s.state = {1, 2, 0.25, 0.5, 0.001, 0.002};
  return s;
}

std::int64_t setup(const std::string& path) {
  std::filesystem::remove(path);
  std::filesystem::remove(path + "-wal");
  std::filesystem::remove(path + "-shm");
  SessionStore store(Database::open(path, OpenMode::create_or_open).value());
  const auto protocol = store.add_protocol("bench", "bench").value();
  const auto participant = store.add_participant({"B01", 0.063, DominantEye::right}).value();
  SessionRecord r;
  r.protocol_id = protocol;
  r.participant_id = participant;
  r.software_version = r.software_commit = r.renderer_device = r.renderer_driver = "bench";
  return store.create_session(r).value();
}

// The same INSERT the writer uses, one prepared statement, batches of 8192
// rows per transaction, synchronous=NORMAL: the best a plain loop does.
double raw_loop_rows_per_s(const std::string& path, std::int64_t session, std::int64_t rows) {
  auto c = Connection::open(path, OpenFlags::read_write);
  configure_connection(c, false);
  Statement st(c,
               "INSERT INTO tracking_samples (session_id, trial_id, frame_index, device, t_ns, "
               "lab_px_m, lab_py_m, lab_pz_m, lab_qx, lab_qy, lab_qz, lab_qw, position_valid, "
               "orientation_valid, virtual_pose, physical_edge, virtual_edge, laps, "
               "anchor_fraction, coherence_error_m, coherence_error_rad) VALUES (?1, ?2, ?3, ?4, "
               "?5, ?6, ?7, ?8, ?9, ?10, ?11, ?12, ?13, ?14, ?15, ?16, ?17, ?18, ?19, ?20, ?21)");
  const char* devices[] = {"head", "left_hand", "right_hand"};
  const auto t0 = Clock::now();
  for (std::int64_t i = 0; i < rows;) {
    Transaction txn(c);
    for (std::int64_t k = 0; k < 8192 && i < rows; ++k, ++i) {
      const TrackingSample s = sample(session, i);
      st.bind(1, s.session_id).bind_null(2).bind(3, s.frame_index).bind_static(4, devices[i % 3]);
      st.bind(5, s.t_ns);
      for (int j = 0; j < 3; ++j) st.bind(6 + j, s.lab_position_m[static_cast<std::size_t>(j)]);
      for (int j = 0; j < 4; ++j) st.bind(9 + j, s.lab_orientation_xyzw[static_cast<std::size_t>(j)]);
      st.bind(13, 1).bind(14, 1);
      st.bind_blob(15, std::as_bytes(std::span<const double, 16>(s.virtual_pose)));
      st.bind(16, std::int64_t{1}).bind(17, std::int64_t{2}).bind(18, 0.25).bind(19, 0.5);
      st.bind(20, 0.001).bind(21, 0.002);
      st.run();
    }
    txn.commit();
  }
  return static_cast<double>(rows) / std::chrono::duration<double>(Clock::now() - t0).count();
}

double writer_rows_per_s(const std::string& path, std::int64_t session, std::int64_t rows) {
  auto writer = SampleWriter::open(path).value();
  const auto t0 = Clock::now();
  for (std::int64_t i = 0; i < rows; ++i) {
    const TrackingSample s = sample(session, i);
    while (!writer->push_tracking(s)) std::this_thread::yield();  // unpaced: wait, do not drop
  }
  if (!writer->flush(std::chrono::minutes(5))) std::fprintf(stderr, "flush failed\n");
  return static_cast<double>(rows) / std::chrono::duration<double>(Clock::now() - t0).count();
}

}  // namespace

int main(int argc, char** argv) {
  double seconds = 60.0;
  std::string dir = std::filesystem::temp_directory_path().string();
  std::int64_t rows = 600'000;
  std::string views = "same";
  for (int i = 1; i + 1 < argc; i += 2) {
    if (!std::strcmp(argv[i], "--seconds")) seconds = std::stod(argv[i + 1]);
    else if (!std::strcmp(argv[i], "--dir")) dir = argv[i + 1];
    else if (!std::strcmp(argv[i], "--rows")) rows = std::stoll(argv[i + 1]);
    else if (!std::strcmp(argv[i], "--views")) views = argv[i + 1];
  }
  if (views != "same" && views != "changing" && views != "none") {
    std::fprintf(stderr, "--views: expected same, changing or none\n");
    return 2;
  }
  const std::string path = dir + "/curvlab_bench_logger.db";

  // 1. Paced: the frame loop's real load, in real time.
  std::int64_t session = setup(path);
  SampleWriterStats st;
  double wall_s = 0.0, cpu_s = 0.0, max_push_us = 0.0;
  {
    auto writer = SampleWriter::open(path).value();
    const auto start = Clock::now();
    const double cpu0 = process_cpu_s();
    std::int64_t ms = 0, frames = 0, i = 0;
    const auto total_ms = static_cast<std::int64_t>(seconds * 1000.0);
    for (; ms < total_ms; ++ms) {
      std::this_thread::sleep_until(start + std::chrono::milliseconds(ms));
      const auto p0 = Clock::now();
      for (int d = 0; d < 3; ++d) writer->push_tracking(sample(session, i++));
      while (frames * 1000 < ms * 90) {
        FrameRecord f;
        f.session_id = session;
        f.frame_index = frames++;
        f.t_ns = ms * 1'000'000;
        f.cpu_time_ns = 2'000'000;
        f.views = 2;
        f.passes = 2;
        f.draws = 12;
        f.triangles = 5000;
        if (views != "none") {
          // Two eyes 63 mm apart with an asymmetric field of view; "changing"
          // moves them a micrometre every frame, as runtime views may.
          f.has_view_geometry = true;
          f.view_geometry.width_px = 1832;
          f.view_geometry.height_px = 1920;
          const double jitter = views == "changing" ? 1e-6 * static_cast<double>(frames % 2) : 0.0;
          for (std::size_t e = 0; e < 2; ++e) {
            f.view_geometry.eyes[e].position_m = {e == 0 ? -0.0315 + jitter : 0.0315, 0.0, 0.0};
            f.view_geometry.eyes[e].fov_rad = {e == 0 ? -0.87 : -0.72, e == 0 ? 0.72 : 0.87, 0.80, -0.88};
          }
        }
        writer->push_frame(f);
      }
      max_push_us = std::max(max_push_us, std::chrono::duration<double, std::micro>(Clock::now() - p0).count());
    }
    if (!writer->flush()) std::fprintf(stderr, "flush failed: %s\n", writer->last_error().c_str());
    wall_s = std::chrono::duration<double>(Clock::now() - start).count();
    cpu_s = process_cpu_s() - cpu0;
    st = writer->stats();
  }
  auto bytes = [](const std::string& file) {
    std::error_code ec;
    const auto n = std::filesystem::file_size(file, ec);
    return ec ? std::uintmax_t{0} : n;
  };
  const auto file_bytes = bytes(path) + bytes(path + "-wal");
  std::printf("sustained logging, paced in real time (%s), eye geometry: %s\n", path.c_str(), views.c_str());
  std::printf("| seconds | samples | frames | dropped | committed | transactions | writer CPU | process CPU | max push | file MiB |\n");
  std::printf("|---|---|---|---|---|---|---|---|---|---|\n");
  std::printf("| %.1f | %llu | %llu | %llu | %llu | %llu | %.2f %% | %.2f %% | %.1f us | %.2f |\n\n", wall_s,
              static_cast<unsigned long long>(st.pushed_tracking),
              static_cast<unsigned long long>(st.pushed_frames),
              static_cast<unsigned long long>(st.dropped_tracking + st.dropped_frames),
              static_cast<unsigned long long>(st.committed_tracking + st.committed_frames),
              static_cast<unsigned long long>(st.transactions), 100.0 * st.writer_cpu_s / wall_s,
              100.0 * cpu_s / wall_s, max_push_us, static_cast<double>(file_bytes) / (1 << 20));

  // 2. Unpaced: the writer against a raw loop on the same rows and disk.
  session = setup(path);
  const double raw = raw_loop_rows_per_s(path, session, rows);
  session = setup(path);
  const double logged = writer_rows_per_s(path, session, rows);
  std::printf("unpaced throughput, %lld tracking rows each\n", static_cast<long long>(rows));
  std::printf("| path | rows/s | ratio to raw |\n|---|---|---|\n");
  std::printf("| raw prepared-statement loop | %.0f | 1.00 |\n", raw);
  std::printf("| SampleWriter (ring + writer thread) | %.0f | %.2f |\n", logged, logged / raw);
  std::printf("\nneeded for 3 devices at 1 kHz: 3000 rows/s; target ratio >= 0.80\n");
  std::filesystem::remove(path);
  std::filesystem::remove(path + "-wal");
  std::filesystem::remove(path + "-shm");
  return st.dropped_tracking + st.dropped_frames == 0 ? 0 : 1;
}

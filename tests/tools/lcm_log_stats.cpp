// lcm-log-stats (test tool): per-channel traffic of an LCM log, for the closing figures of
// the onboard/ground tests ("what crosses the link should stay under 1 Mbit/s").
//   lcm-log-stats LOG [--json FILE]
// For each channel: messages, total payload bytes, bytes per second and kbit/s, the rates
// over the whole log's duration (first to last event of any channel, log timestamps in us).
// Printed as a table on stdout (one line per channel, then "total"); --json also writes
//   {"log": ..., "duration_s": ..., "channels": {"NAME": {"messages": .., "bytes": ..,
//    "bytes_per_s": .., "kbit_per_s": ..}, ...}, "total": {...}}
// Payload bytes only (no LCM or UDP headers). Exit 1 if the log cannot be read.
#include <lcm/lcm-cpp.hpp>

#include <cstdio>
#include <fstream>
#include <iostream>
#include <map>

#include "common/cli.h"
#include "common/process.h"

using namespace rgbdslam;

namespace {

struct ChannelTraffic {
  long messages = 0;
  long long bytes = 0;
};

struct LogTraffic {
  std::map<std::string, ChannelTraffic> channels;
  ChannelTraffic total;
  int64_t first_utime = 0, last_utime = 0;
  double durationSeconds() const { return (last_utime - first_utime) * 1e-6; }
};

// Rate over the log's duration; 0 for a log of one instant (a single event).
double perSecond(double amount, double seconds) { return seconds > 0 ? amount / seconds : 0.0; }

std::string jsonEscape(const std::string& text) {
  std::string out;
  for (char c : text) {
    if (c == '"' || c == '\\') out += '\\';
    if (static_cast<unsigned char>(c) < 0x20) continue;
    out += c;
  }
  return out;
}

std::string jsonEntry(const ChannelTraffic& t, double seconds) {
  char buffer[200];
  std::snprintf(buffer, sizeof(buffer),
                "{\"messages\": %ld, \"bytes\": %lld, \"bytes_per_s\": %.1f, \"kbit_per_s\": %.3f}",
                t.messages, t.bytes, perSecond(static_cast<double>(t.bytes), seconds),
                perSecond(t.bytes * 8e-3, seconds));
  return buffer;
}

void printTable(const LogTraffic& traffic) {
  const double seconds = traffic.durationSeconds();
  std::printf("duration_s %.3f\n%-24s %10s %14s %14s %12s\n", seconds, "channel", "messages", "bytes",
              "bytes_per_s", "kbit_per_s");
  auto line = [seconds](const std::string& name, const ChannelTraffic& t) {
    std::printf("%-24s %10ld %14lld %14.1f %12.3f\n", name.c_str(), t.messages, t.bytes,
                perSecond(static_cast<double>(t.bytes), seconds), perSecond(t.bytes * 8e-3, seconds));
  };
  for (const auto& [name, t] : traffic.channels) line(name, t);
  line("total", traffic.total);
}

bool writeJson(const std::string& path, const std::string& log, const LogTraffic& traffic) {
  const double seconds = traffic.durationSeconds();
  std::ofstream out(path);
  out << "{\"log\": \"" << jsonEscape(log) << "\", \"duration_s\": " << seconds << ", \"channels\": {";
  bool first = true;
  for (const auto& [name, t] : traffic.channels) {
    out << (first ? "" : ", ") << "\"" << jsonEscape(name) << "\": " << jsonEntry(t, seconds);
    first = false;
  }
  out << "}, \"total\": " << jsonEntry(traffic.total, seconds) << "}\n";
  return static_cast<bool>(out);
}

}  // namespace

int main(int argc, char** argv) {
  CommandLine cli("lcm-log-stats", "Test tool: messages, bytes and bit rate per channel of an LCM log.");
  cli.positional("LOG", "LCM log file (lcm-logger)");
  cli.option("json", "FILE", "also write the figures as JSON to FILE");
  if (Status s = cli.parse(argc, argv); !s) return usageError("lcm-log-stats", s.error());
  if (cli.helpRequested()) return std::cout << cli.helpText(), 0;
  const std::string path = cli.positionalValue(0);
  lcm::LogFile log(path, "r");
  if (!log.good()) {
    std::cerr << "lcm-log-stats: error: cannot read " << path << "\n";
    return 1;
  }
  LogTraffic traffic;
  for (const lcm::LogEvent* event = log.readNextEvent(); event; event = log.readNextEvent()) {
    if (traffic.total.messages == 0) traffic.first_utime = event->timestamp;
    traffic.last_utime = event->timestamp;
    ChannelTraffic& t = traffic.channels[event->channel];
    ++t.messages, ++traffic.total.messages;
    t.bytes += event->datalen, traffic.total.bytes += event->datalen;
  }
  printTable(traffic);
  if (cli.has("json") && !writeJson(cli.get("json"), path, traffic)) {
    std::cerr << "lcm-log-stats: error: cannot write " << cli.get("json") << "\n";
    return 1;
  }
  return 0;
}

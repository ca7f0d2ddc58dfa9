// usar-replay's pacing shim, preloaded (LD_PRELOAD) into a team's ROS 1 nodes.
//
// Why: usar advances /clock one tick at a time and starts the next tick when the graph is idle
// (docs/ros1.md, "Pacing"). A node that polls without sleeping (`while (ros::ok()) { publish;
// ros::spinOnce(); }`, or `while (ac.getState() != SUCCEEDED) ROS_INFO("Moving");`) never
// looks idle: on Gazebo it burns a CPU and works, under usar every tick waited for the wall cap
// (0.33x real time, not repeatable) or the start-up gate gave up. Such a loop has nothing new
// to do until sim time moves on, so this shim makes it wait for that, as a sim-time sleep does
// (on the process's clock, below, until ros::Time::now() changes): the loop then runs its body
// a fixed number of times per tick and looks to usar's idle check like a node paced by
// ros::Rate. roscpp's own sim-time sleeps (Duration::sleep, Rate::sleep, Time::sleepUntil) wait
// on that clock too instead of napping 1 ms at a time.
//
// The policy, per thread, at each poll point (ros::spinOnce(), CallbackQueue::callAvailable()
// with a zero timeout, and ros::console::print(), ROS_INFO's entry, outside any callback):
//   - sim time changed since this thread's previous poll point: go on (a new tick);
//   - the thread executed callbacks at its previous spin: go on (it is still reacting), with
//     a new budget;
//   - else count it (log lines only on the main thread or a thread that spins itself: never
//     on roscpp's own threads); past a small budget per tick (kSpinBudget spins, kPrintBudget log lines,
//     so a node that logs a few lines in one go, or spins twice in one loop, is not delayed)
//     the thread waits until sim time changes (or ros::ok() turns false).
// Nothing here reads the wall clock to decide: how many times a loop body runs in a tick
// depends on the ticks and the messages only, so two recordings are the same.
//
// Only sim time is paced: with wall time, ros::Time::now() changes at every call and the shim
// never waits. It links nothing of ROS: the real functions are found with dlsym at run time,
// so in a process without roscpp (sh, rosmaster, a rospy node) nothing here is ever called.
//
// Symbols are named by their Itanium C++ mangled names (`nm -D libroscpp.so`), so this file
// needs no ROS header: ros::Time and ros::WallDuration are two 32-bit ints, passed in one
// register; the other arguments are forwarded untouched.

#include <dlfcn.h>
#include <linux/futex.h>
#include <sys/syscall.h>
#include <time.h>
#include <unistd.h>

#include <atomic>
#include <cstdarg>
#include <climits>
#include <cstdint>
#include <cstdio>

namespace {

struct RosTime {  // ros::Time's and ros::WallDuration's layout
  int32_t sec;
  int32_t nsec;
};

constexpr int kSpinBudget = 1;   // idle spins per tick before a thread waits
constexpr int kPrintBudget = 4;  // log lines per tick (outside callbacks) before it waits

using NowFn = RosTime (*)();
using BoolFn = bool (*)();
using VoidFn = void (*)();
using QueueFn = void* (*)();
using EmptyFn = bool (*)(void*);
using CallAvailableFn = void (*)(void*, RosTime);
using PrintFn = void (*)(void*, void*, int, const char*, int, const char*, const char*, ...);
using PrintStreamFn = void (*)(void*, void*, int, const void*, const char*, int, const char*);

constexpr const char* kNow = "_ZN3ros4Time3nowEv";
constexpr const char* kSetNow = "_ZN3ros4Time6setNowERKS0_";
constexpr const char* kTimeShutdown = "_ZN3ros4Time8shutdownEv";
constexpr const char* kUseSystemTime = "_ZN3ros4Time13useSystemTimeEv";
constexpr const char* kDurationSleep = "_ZNK3ros8Duration5sleepEv";
constexpr const char* kSleepUntil = "_ZN3ros4Time10sleepUntilERKS0_";
constexpr const char* kOk = "_ZN3ros2okEv";
constexpr const char* kSpinOnce = "_ZN3ros8spinOnceEv";
constexpr const char* kGlobalQueue = "_ZN3ros22getGlobalCallbackQueueEv";
constexpr const char* kIsEmpty = "_ZN3ros13CallbackQueue7isEmptyEv";
constexpr const char* kCallAvailable = "_ZN3ros13CallbackQueue13callAvailableENS_12WallDurationE";
constexpr const char* kPrint =
    "_ZN3ros7console5printEPNS0_10FilterBaseEPvNS0_6levels5LevelEPKciS7_S7_z";
constexpr const char* kPrintStream =
    "_ZN3ros7console5printEPNS0_10FilterBaseEPvNS0_6levels5LevelERKNSt7__cxx1118basic_"
    "stringstreamIcSt11char_traitsIcESaIcEEEPKciSF_";

template <typename F>
F next(const char* name) {  // the real function, after this library in the search order
  return reinterpret_cast<F>(dlsym(RTLD_NEXT, name));
}

template <typename F>
F any(const char* name) {  // a function wherever the process has it (nullptr: not loaded)
  return reinterpret_cast<F>(dlsym(RTLD_DEFAULT, name));
}

struct Thread {
  bool seen = false;     // a poll point seen since the thread began
  int64_t last = 0;      // sim time at the previous poll point, ns
  bool reacted = false;  // callbacks were waiting at the last spin
  int spins = 0;         // idle spins at this sim time
  int prints = 0;        // log lines at this sim time
  int depth = 0;         // inside a spin (callbacks run there are reactions, not polls)
  bool spun = false;     // the thread polled the queue itself once (a loop of the package's)
};

thread_local Thread t_state;

enum class Kind { kSpin, kPrint };

// Sim time now in ns, or -1 when roscpp's time is not usable (not initialised: it throws).
int64_t sim_now() {
  static NowFn now = any<NowFn>(kNow);
  if (now == nullptr) return -1;
  try {
    RosTime t = now();
    return static_cast<int64_t>(t.sec) * 1000000000LL + t.nsec;
  } catch (...) {
    return -1;
  }
}

bool ros_ok() {
  static BoolFn ok = any<BoolFn>(kOk);
  return ok != nullptr && ok();
}

// The process's sim-time clock: bumped, and its waiters woken, each time roscpp sets the time
// (its /clock subscription calls ros::Time::setNow) and when ros::Time shuts down.
std::atomic<uint32_t> g_clock{0};
std::atomic<bool> g_stopped{false};  // ros::Time::shutdown() was called

void bump_clock() {
  g_clock.fetch_add(1, std::memory_order_release);
  syscall(SYS_futex, reinterpret_cast<uint32_t*>(&g_clock), FUTEX_WAKE_PRIVATE, INT_MAX, nullptr,
          nullptr, 0);
}

// Wait until the clock moves past `seen` (read before the caller last looked at the time, so a
// change in between returns at once). The one-second wall-clock limit is only a safety net: the
// caller looks at the time again and waits once more.
void wait_clock(uint32_t seen) {
  const timespec limit{1, 0};
  syscall(SYS_futex, reinterpret_cast<uint32_t*>(&g_clock), FUTEX_WAIT_PRIVATE, seen, &limit,
          nullptr, 0);
}

bool sim_time() {
  static BoolFn use_system_time = any<BoolFn>(kUseSystemTime);
  return use_system_time != nullptr && !use_system_time();
}

// Wait until sim time moves on from `last` (-1: shutting down).
int64_t wait_for_new_time(int64_t last) {
  for (;;) {
    uint32_t seen = g_clock.load(std::memory_order_acquire);
    if (!ros_ok()) return -1;
    int64_t now = sim_now();
    if (now != last) return now;
    wait_clock(seen);
  }
}

// A thread whose log lines may be a busy loop's: the main thread, or one that spins a queue
// itself. roscpp's own threads (network, XML-RPC, timers) never wait here for a warning burst.
bool paced_printer(const Thread& s) {
  return s.spun || syscall(SYS_gettid) == getpid();
}

void poll_point(Kind kind) {
  Thread& s = t_state;
  if (s.depth > 0) return;  // a callback's own log lines: a reaction
  if (kind == Kind::kSpin) s.spun = true;
  else if (!paced_printer(s)) return;
  int64_t now = sim_now();
  if (now < 0) return;
  if (s.seen && now == s.last && !s.reacted) {
    int& count = kind == Kind::kSpin ? s.spins : s.prints;
    int budget = kind == Kind::kSpin ? kSpinBudget : kPrintBudget;
    if (++count <= budget) return;
    now = wait_for_new_time(s.last);
    if (now < 0) return;  // shutting down: let the loop see it
  }
  if (!s.seen || now != s.last || s.reacted) {  // a new tick, or still reacting: a new budget
    s.spins = 0;
    s.prints = 0;
  }
  s.seen = true;
  s.last = now;
  s.reacted = false;
}

struct Inside {  // marks a spin, exception-safe
  Inside() { ++t_state.depth; }
  ~Inside() { --t_state.depth; }
};

bool has_work(void* queue) {
  static EmptyFn is_empty = any<EmptyFn>(kIsEmpty);
  return queue != nullptr && is_empty != nullptr && !is_empty(queue);
}

}  // namespace

// ros::spinOnce()
extern "C" void usar_spin_once() __asm__("_ZN3ros8spinOnceEv");
extern "C" void usar_spin_once() {
  static VoidFn real = next<VoidFn>(kSpinOnce);
  static QueueFn global = any<QueueFn>(kGlobalQueue);
  if (t_state.depth == 0) {
    poll_point(Kind::kSpin);
    if (global != nullptr && has_work(global())) t_state.reacted = true;
  }
  Inside inside;
  real();
}

// ros::CallbackQueue::callAvailable(ros::WallDuration): a zero timeout is a poll, any other a
// blocking wait (ros::spin(), AsyncSpinner), which the idle check already sees as waiting.
extern "C" void usar_call_available(void* queue, RosTime timeout)
    __asm__("_ZN3ros13CallbackQueue13callAvailableENS_12WallDurationE");
extern "C" void usar_call_available(void* queue, RosTime timeout) {
  static CallAvailableFn real = next<CallAvailableFn>(kCallAvailable);
  if (t_state.depth == 0 && timeout.sec == 0 && timeout.nsec == 0) {
    poll_point(Kind::kSpin);
    if (has_work(queue)) t_state.reacted = true;
  }
  Inside inside;
  real(queue, timeout);
}

// ros::console::print(FilterBase*, void*, Level, file, line, function, const char* fmt, ...):
// the line is formatted here and handed on as "%s", which rosconsole prints the same.
extern "C" void usar_print(void* filter, void* logger, int level, const char* file, int line,
                           const char* function, const char* fmt, ...)
    __asm__("_ZN3ros7console5printEPNS0_10FilterBaseEPvNS0_6levels5LevelEPKciS7_S7_z");
extern "C" void usar_print(void* filter, void* logger, int level, const char* file, int line,
                           const char* function, const char* fmt, ...) {
  static PrintFn real = next<PrintFn>(kPrint);
  poll_point(Kind::kPrint);
  va_list args;
  va_start(args, fmt);
  va_list copy;
  va_copy(copy, args);
  int n = std::vsnprintf(nullptr, 0, fmt, copy);
  va_end(copy);
  char small[512];
  char* text = small;
  if (n >= static_cast<int>(sizeof small)) text = new char[n + 1];
  if (n >= 0) std::vsnprintf(text, static_cast<size_t>(n) + 1, fmt, args);
  va_end(args);
  real(filter, logger, level, file, line, function, "%s", n >= 0 ? text : "");
  if (text != small) delete[] text;
}

// ros::console::print(..., const std::stringstream&, ...): ROS_INFO_STREAM's entry.
extern "C" void usar_print_stream(void* filter, void* logger, int level, const void* ss,
                                  const char* file, int line, const char* function)
    __asm__(
        "_ZN3ros7console5printEPNS0_10FilterBaseEPvNS0_6levels5LevelERKNSt7__cxx1118basic_"
        "stringstreamIcSt11char_traitsIcESaIcEEEPKciSF_");
extern "C" void usar_print_stream(void* filter, void* logger, int level, const void* ss,
                                  const char* file, int line, const char* function) {
  static PrintStreamFn real = next<PrintStreamFn>(kPrintStream);
  poll_point(Kind::kPrint);
  real(filter, logger, level, ss, file, line, function);
}

// ros::Time::setNow(const Time&): roscpp's /clock callback. The new time wakes the threads
// sleeping in sim time at once, where roscpp's own sleeps notice it at their next 1 ms nap.
using SetNowFn = void (*)(const RosTime*);
extern "C" void usar_set_now(const RosTime* t) __asm__("_ZN3ros4Time6setNowERKS0_");
extern "C" void usar_set_now(const RosTime* t) {
  static SetNowFn real = next<SetNowFn>(kSetNow);
  real(t);
  bump_clock();
}

// ros::Time::shutdown(): the end of every sim-time sleep (roscpp's g_stopped).
extern "C" void usar_time_shutdown() __asm__("_ZN3ros4Time8shutdownEv");
extern "C" void usar_time_shutdown() {
  static VoidFn real = next<VoidFn>(kTimeShutdown);
  real();
  g_stopped.store(true, std::memory_order_release);
  bump_clock();
}

// ros::Duration::sleep() const (ros::Rate::sleep() calls it) and ros::Time::sleepUntil(): in sim
// time, roscpp's versions nap 1 ms at a time until ros::Time::now() reaches the end, so a
// sleeping node looks idle to usar while it has not yet seen the new /clock, and usar must wait
// for every such napper to wake once more before it may call the graph idle (a millisecond or
// more a tick). These wait on the process's clock instead: the thread wakes when the time is
// set, as part of taking in /clock, and is blocked (not polling) in between. Same results as
// roscpp's: true once the end is reached, false if time went backwards or ros::Time shut down
// first. With wall time (no /use_sim_time) roscpp's own run.
using DurationSleepFn = bool (*)(const RosTime*);

namespace {

int64_t ns_of(const RosTime& t) { return static_cast<int64_t>(t.sec) * 1000000000LL + t.nsec; }

enum class Slept { kReached, kNoWait, kBackwards, kStopped };

// roscpp's sim-time loop, waiting on the clock instead of napping. `from_zero` >= 0: a sleep
// of that many ns begun at time 0 (before the first /clock), which, as roscpp's, counts from
// the first time set after it began.
Slept sleep_until_ns(int64_t start, int64_t end, int64_t from_zero = -1) {
  bool waited = false;
  for (;;) {
    uint32_t seen = g_clock.load(std::memory_order_acquire);
    if (g_stopped.load(std::memory_order_acquire)) return Slept::kStopped;
    int64_t now = sim_now();
    if (now < 0) return Slept::kStopped;
    if (waited && start == 0 && from_zero >= 0) {
      start = now;  // roscpp: "wait for the first actual time to arrive before starting"
      end = now == 0 ? INT64_MAX : now + from_zero;
    }
    if (now < start) return Slept::kBackwards;
    if (now >= end) return waited ? Slept::kReached : Slept::kNoWait;
    wait_clock(seen);
    waited = true;
  }
}

}  // namespace

extern "C" bool usar_duration_sleep(const RosTime* self) __asm__("_ZNK3ros8Duration5sleepEv");
extern "C" bool usar_duration_sleep(const RosTime* self) {
  static DurationSleepFn real = next<DurationSleepFn>(kDurationSleep);
  int64_t start = sim_time() ? sim_now() : -1;
  if (start < 0) return real(self);
  if (start == 0) return sleep_until_ns(0, INT64_MAX, ns_of(*self)) == Slept::kReached;
  return sleep_until_ns(start, start + ns_of(*self)) == Slept::kReached;  // false: never waited
}

extern "C" bool usar_sleep_until(const RosTime* end) __asm__("_ZN3ros4Time10sleepUntilERKS0_");
extern "C" bool usar_sleep_until(const RosTime* end) {
  static DurationSleepFn real = next<DurationSleepFn>(kSleepUntil);
  int64_t start = sim_time() ? sim_now() : -1;
  if (start < 0) return real(end);
  return sleep_until_ns(start, ns_of(*end)) != Slept::kBackwards;  // roscpp: true when stopped
}

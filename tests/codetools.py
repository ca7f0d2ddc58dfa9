"""Small C++ packages for the code grade's tests, written into a test's tmp_path.

Every package here is this project's own text, shaped like a course submission: a
``template`` (as the course hands out: one ``main.cpp`` with free functions, a long main and
commented-out lines of its own, and the handout's PDF in ``doc/``), an OOP team (``alpha``:
documented classes, a thin main, its own Doxygen HTML, a Doxyfile, ``doc/instructions.txt``),
``alpha``'s copy with every identifier renamed and its functions reordered, an honest team
sharing only the template (``beta``), a team with no class, commented-out blocks and unused
functions (``procedural``), and one whose committed HTML documents ``alpha`` (``borrowed``).
"""

from __future__ import annotations

import re
from pathlib import Path

PACKAGE_XML = (
    '<?xml version="1.0"?>\n<package format="2">\n  <name>{name}</name>\n  <version>0.1.0'
    "</version>\n  <description>d</description>\n  <maintainer email=\"a@b.c\">a</maintainer>"
    "\n  <license>MIT</license>\n  <buildtool_depend>catkin</buildtool_depend>\n</package>\n"
)
CMAKE = (
    "cmake_minimum_required(VERSION 3.0.2)\nproject({name})\nfind_package(catkin REQUIRED "
    "COMPONENTS roscpp)\ncatkin_package()\nadd_executable(main src/main.cpp)\n"
)

TEMPLATE_MAIN = """\
#include <ros/ros.h>
#include <tf2_ros/transform_broadcaster.h>

void broadcast() {
  //for broadcaster
  static tf2_ros::TransformBroadcaster br;
  geometry_msgs::TransformStamped transformStamped;
  transformStamped.header.stamp = ros::Time::now();
  transformStamped.header.frame_id = "explorer_tf/camera_rgb_optical_frame";
  transformStamped.child_frame_id = "my_frame";
  transformStamped.transform.translation.x = 0.5;
  transformStamped.transform.rotation.w = 1;
  br.sendTransform(transformStamped);
}

void listen(tf2_ros::Buffer& tfBuffer) {
  geometry_msgs::TransformStamped transformStamped;
  try {
    transformStamped = tfBuffer.lookupTransform("map", "my_frame", ros::Time(0));
    auto trans_x = transformStamped.transform.translation.x;
    ROS_INFO_STREAM("Position in map frame: [" << trans_x << "]");
  }
  catch (tf2::TransformException& ex) {
    ROS_WARN("%s", ex.what());
    ros::Duration(1.0).sleep();
  }
}

int main(int argc, char** argv) {
  bool explorer_goal_sent = false;
  ros::init(argc, argv, "simple_navigation_goals");
  ros::NodeHandle nh;
  // explorer_client.waitForResult();
  // ROS_INFO("Sending goal");
  // follower_client.sendGoal(follower_goal);
  tf2_ros::Buffer tfBuffer;
  tf2_ros::TransformListener tfListener(tfBuffer);
  ros::Rate loop_rate(10);
  while (ros::ok()) {
    if (!explorer_goal_sent) {
      explorer_goal_sent = true;
    }
    broadcast();
    listen(tfBuffer);
    //ros::spinOnce(); //uncomment this if you have subscribers in your code
    loop_rate.sleep();
  }
}
"""

ALPHA_H = """\
#ifndef ALPHA_ROBOTS_H
#define ALPHA_ROBOTS_H
#include <ros/ros.h>
#include <array>
#include <vector>

namespace alpha {

/** @brief The explorer: visits each target, then searches for its marker. */
class Explorer {
 public:
  /** @brief Reads the targets from the parameter server. */
  explicit Explorer(ros::NodeHandle* nh);
  /** @brief One step of the explorer's state machine; true when it is done. */
  bool step();
  /** @brief The marker poses found so far. */
  const std::vector<double>& markers() const { return markers_; }

 private:
  /** @brief Turns in place until a marker is seen. */
  void search_marker(double speed);
  /** @brief Picks the next target, or home. */
  int next_target(int current);
  ros::NodeHandle* nh_;
  std::vector<double> markers_;
  int target_index_{0};
};

/** @brief The follower: visits the markers in the order of their ids. */
class Follower {
 public:
  /** @brief Starts the follower on the explorer's markers. */
  explicit Follower(const std::vector<double>& markers);
  /** @brief One step; true when it is back home. */
  bool drive_step();

 private:
  std::vector<double> goals_;
  std::size_t goal_{0};
};

}  // namespace alpha
#endif
"""

ALPHA_CPP = """\
#include "alpha/robots.h"

#include <algorithm>
#include <cmath>

namespace alpha {

Explorer::Explorer(ros::NodeHandle* nh) : nh_(nh) {
  std::vector<double> targets;
  nh_->getParam("/aruco_lookup_locations/target_1", targets);
  for (std::size_t i = 0; i < targets.size(); ++i) {
    markers_.push_back(targets[i] * 0.5 + std::sqrt(static_cast<double>(i)));
  }
}

bool Explorer::step() {
  if (target_index_ >= static_cast<int>(markers_.size())) {
    return true;
  }
  search_marker(0.3 + 0.1 * target_index_);
  target_index_ = next_target(target_index_);
  ROS_INFO_STREAM("explorer at target " << target_index_ << " of " << markers_.size());
  return false;
}

void Explorer::search_marker(double speed) {
  double turned = 0.0;
  while (turned < 6.28 && ros::ok()) {
    turned += speed * 0.1;
    if (std::fabs(std::sin(turned)) > 0.99) {
      markers_.push_back(turned);
      break;
    }
  }
}

int Explorer::next_target(int current) {
  const int last = static_cast<int>(markers_.size()) - 1;
  return std::min(current + 1, last + 1);
}

Follower::Follower(const std::vector<double>& markers) : goals_(markers) {
  std::sort(goals_.begin(), goals_.end());
  goals_.push_back(-4.0);
}

bool Follower::drive_step() {
  if (goal_ >= goals_.size()) {
    return true;
  }
  const double goal = goals_[goal_];
  ROS_INFO("follower driving to %f (goal %zu of %zu)", goal, goal_ + 1, goals_.size());
  goal_ += 1;
  return goal_ == goals_.size();
}

}  // namespace alpha
"""

ALPHA_MAIN = """\
#include <ros/ros.h>
#include "alpha/robots.h"

/** @brief Runs the explorer, then the follower, then stops. */
int main(int argc, char** argv) {
  ros::init(argc, argv, "alpha");
  ros::NodeHandle nh;
  alpha::Explorer explorer(&nh);
  ros::Rate rate(10);
  while (ros::ok() && !explorer.step()) {
    rate.sleep();
  }
  alpha::Follower follower(explorer.markers());
  while (ros::ok() && !follower.drive_step()) {
    rate.sleep();
  }
  ros::shutdown();
}
"""

BETA_MAIN = """\
#include <ros/ros.h>
#include <map>
#include <string>

/** @brief A lookup of the fiducial ids a robot has seen, by id. */
class MarkerBook {
 public:
  /** @brief Records a sighting of marker `id` at (x, y); keeps the nearest. */
  void record(int id, double x, double y, double range) {
    auto found = book_.find(id);
    if (found == book_.end() || found->second.range > range) {
      book_[id] = Sighting{x, y, range};
    }
  }
  /** @brief How many different markers were seen. */
  std::size_t count() const { return book_.size(); }
  /** @brief Prints every marker in the order of its id. */
  void print() const {
    for (const auto& entry : book_) {
      ROS_INFO("marker %d at (%.2f, %.2f)", entry.first, entry.second.x, entry.second.y);
    }
  }

 private:
  struct Sighting {
    double x;
    double y;
    double range;
  };
  std::map<int, Sighting> book_;
};

/** @brief Records four fake sightings and prints them. */
int main(int argc, char** argv) {
  ros::init(argc, argv, "beta");
  MarkerBook book;
  for (int k = 0; k < 4; ++k) {
    book.record(3 - k, 1.5 * k, -2.0 + k, 0.4 * (k + 1));
  }
  if (book.count() == 4) {
    book.print();
  }
  return 0;
}
"""

PROCEDURAL_MAIN = """\
#include <ros/ros.h>
#include <vector>

double helper_one(double x) { return x * 2.0; }

double helper_two(double x) { return x + 2.0; }

int unused_counter(int a, int b) { return a * b + 7; }

double never_called(double v) { return v / 3.0; }

int main(int argc, char** argv) {
  ros::init(argc, argv, "procedural");
  ros::NodeHandle nh;
  std::vector<double> goals{1.0, 2.0, 3.0, 4.0};
  int unread = 4;
  unread = 5;
  // std::vector<double> old_goals{0.5, 1.5};
  // for (auto g : old_goals) {
  //   ROS_INFO("old goal %f", g);
  //   helper_two(g);
  // }
  // ros::spinOnce();
  double total = 0.0;
  for (double g : goals) {
    total += helper_one(g);
  }
  /*
  if (total > 10.0) {
    ROS_WARN("far");
  }
  */
  ROS_INFO("total %f", total);
  ros::Rate rate(10);
  int ticks = 0;
  while (ros::ok() && ticks < 100) {
    ticks += 1;
    if (ticks % 10 == 0) {
      ROS_INFO("tick %d", ticks);
    }
    if (ticks % 25 == 0) {
      ROS_INFO("quarter %d", ticks / 25);
    }
    rate.sleep();
  }
  ROS_INFO("done after %d ticks", ticks);
  return 0;
}
"""

RENAMES = {
    "alpha": "gang", "Explorer": "Scout", "Follower": "Tracker", "step": "tick",
    "markers_": "spots_", "markers": "spots", "search_marker": "look_around",
    "next_target": "advance", "target_index_": "cursor_", "drive_step": "move_once",
    "goals_": "waypoints_", "goal_": "slot_", "turned": "angle", "targets": "wanted",
    "current": "now", "speed": "rate_", "last": "final", "explorer": "scout",
    "follower": "tracker", "nh_": "handle_", "goal": "where",
}  # fmt: skip


def write(root: Path, files: dict[str, str | bytes]) -> Path:
    """Each file under ``root`` (folders made); returns ``root``."""
    for rel, data in files.items():
        path = root / rel
        path.parent.mkdir(parents=True, exist_ok=True)
        if isinstance(data, bytes):
            path.write_bytes(data)
        else:
            path.write_text(data, encoding="utf-8")
    return root


def package(root: Path, name: str, files: dict[str, str | bytes]) -> Path:
    """A catkin package ``name`` at ``root`` holding ``files``."""
    base: dict[str, str | bytes] = {
        "package.xml": PACKAGE_XML.format(name=name),
        "CMakeLists.txt": CMAKE.format(name=name),
    }
    return write(root, {**base, **files})


def alpha_html(names: list[str], files: list[str]) -> dict[str, str | bytes]:
    """Doxygen-shaped HTML pages documenting ``files`` and naming ``names``."""
    out: dict[str, str | bytes] = {
        "doc/html/index.html": "<html><body>" + " ".join(names) + "</body></html>\n"
    }
    for f in files:
        stem, ext = f.rsplit(".", 1)
        out[f"doc/html/{stem.replace('_', '__')}_8{ext}.html"] = f"<html>{f}</html>\n"
    return out


ALPHA_NAMES = ["Explorer", "Follower", "step", "markers", "search_marker", "next_target",
               "drive_step"]  # fmt: skip


def template(root: Path) -> Path:
    return package(root, "final_project", {"src/main.cpp": TEMPLATE_MAIN})


def alpha(root: Path) -> Path:
    return package(
        root,
        "final_project",
        {
            "include/alpha/robots.h": ALPHA_H,
            "src/robots.cpp": ALPHA_CPP,
            "src/main.cpp": ALPHA_MAIN,
            "Doxyfile": "INPUT = src include\nOUTPUT_DIRECTORY = doc\n",
            "doc/instructions.txt": "roslaunch final_project multiple_robots.launch\n",
            **alpha_html(ALPHA_NAMES, ["robots.h", "robots.cpp", "main.cpp"]),
        },
    )


def renamed(text: str) -> str:
    """``text`` with every identifier of :data:`RENAMES` renamed (whole words)."""
    pattern = re.compile(r"\b(" + "|".join(sorted(RENAMES, key=len, reverse=True)) + r")\b")
    return pattern.sub(lambda m: RENAMES[m.group(1)], text)


def _reordered(cpp: str) -> str:
    """``ALPHA_CPP``'s function definitions in reverse order (same namespace around them)."""
    head, body = cpp.split("namespace alpha {\n", 1)
    body, tail = body.rsplit("}  // namespace alpha", 1)
    defs = [d.strip() + "\n" for d in re.split(r"\n(?=\S[^\n]*::[^\n]*\{\n)", body) if d.strip()]
    body = "\n".join(reversed(defs))
    return head + "namespace alpha {\n\n" + body + "\n}  // namespace alpha" + tail


def copy_of_alpha(root: Path) -> Path:
    """``alpha`` renamed and reordered, with no docs of its own."""
    return package(
        root,
        "final_project",
        {
            "include/gang/robots.h": renamed(ALPHA_H),
            "src/robots.cpp": renamed(_reordered(ALPHA_CPP)).replace("alpha/", "gang/"),
            "src/main.cpp": renamed(ALPHA_MAIN),
        },
    )


def beta(root: Path) -> Path:
    return package(root, "final_project", {"src/main.cpp": BETA_MAIN, "README.md": "see doc\n"})


def procedural(root: Path) -> Path:
    return package(root, "final_project", {"src/main.cpp": PROCEDURAL_MAIN})


BORROWED_MAIN = """\
#include <ros/ros.h>

/** @brief Counts down from a start value, one step a tick. */
class Countdown {
 public:
  /** @brief Starts at `from`. */
  explicit Countdown(int from) : left_(from) {}
  /** @brief One tick; false once it reached zero. */
  bool tick() { return --left_ > 0; }

 private:
  int left_;
};

/** @brief Ticks a countdown at 2 Hz. */
int main(int argc, char** argv) {
  ros::init(argc, argv, "borrowed");
  Countdown countdown(8);
  ros::Rate rate(2);
  while (ros::ok() && countdown.tick()) {
    rate.sleep();
  }
}
"""


def borrowed(root: Path) -> Path:
    """Code of its own with ``alpha``'s HTML committed as its docs."""
    return package(
        root,
        "final_project",
        {"src/main.cpp": BORROWED_MAIN,
         **alpha_html(ALPHA_NAMES, ["robots.h", "robots.cpp", "main.cpp"])},
    )  # fmt: skip


def pdf(path: Path, pages: list[str]) -> Path:
    """A PDF of ``pages`` (text lines), made with matplotlib (a dependency of usar's), its
    text extractable (TrueType fonts)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.backends.backend_pdf import PdfPages

    path.parent.mkdir(parents=True, exist_ok=True)
    with matplotlib.rc_context({"pdf.fonttype": 42}), PdfPages(path, metadata={
        "CreationDate": None, "Creator": None, "Producer": None
    }) as out:  # fmt: skip
        for page in pages:
            fig = plt.figure(figsize=(8.5, 11))
            for i, line in enumerate(page.split("\n")):
                fig.text(0.08, 0.95 - 0.025 * i, line, fontsize=9)
            out.savefig(fig)
            plt.close(fig)
    return path


REPORT_PAGES = [
    "1 Introduction\nTwo robots search a building for victims.\nWe solvd the problem wiht "
    "ROS and rviz.",
    "2 Approach\nThe explorer visits each target and broadcasts the marker frame.\n"
    "#include <ros/ros.h>\nstd::vector<double> goals;\nros::spinOnce();\n"
    "Explorer::step(goal);",
    "3 Challenges\nThe follower could not reach the markers.\n4 Resources\nThe course slides.",
]
"""A report with a typo or two, three of the outline's sections and C++ code on page 2."""

HANDOUT_PAGES = [
    "Final Project\n7 Deliverables\nYour group's project submission",
    "8 Getting Help\n9 Grading Rubric\nLive demonstration: 60 pts.",
]


def many_pages_pdf(path: Path, pages: int, first: str = "Lorem ipsum", slow_first: int = 0
                   ) -> Path:  # fmt: skip
    """A PDF of ``pages`` pages, written byte by byte: page 1 has ``first`` (one line); every
    other page shares one content stream of 30 blocks of text, so the file stays small (1,500
    pages: ~270 KB) while a full ``pdftotext`` of it takes tens of seconds (issue 50).
    ``slow_first``: page 1 also draws the shared stream that many times (a first page that
    takes as long to read as that many pages)."""
    text = "Lorem ipsum dolor sit amet consectetur adipiscing elit " * 16
    block = "BT /F1 9 Tf 40 750 Td 11 TL "
    block += " ".join(f"({text[i : i + 90]}) '" for i in range(0, len(text), 90)) + " ET "
    shared = (block * 30).encode()
    opening = f"BT /F1 12 Tf 40 750 Td ({first}) Tj ET".encode()
    objs: list[bytes] = [
        b"<< /Type /Catalog /Pages 2 0 R >>",
        b"<< /Type /Pages /Kids [%s] /Count %d >>"
        % (" ".join(f"{6 + i} 0 R" for i in range(pages)).encode(), pages),
        b"<< /Type /Font /Subtype /Type1 /BaseFont /Helvetica >>",
        b"<< /Length %d >>\nstream\n%s\nendstream" % (len(shared), shared),
        b"<< /Length %d >>\nstream\n%s\nendstream" % (len(opening), opening),
    ]
    contents = b"[5 0 R%s]" % (b" 4 0 R" * slow_first)
    for i in range(pages):
        objs.append(
            b"<< /Type /Page /Parent 2 0 R /MediaBox [0 0 612 792] "
            b"/Resources << /Font << /F1 3 0 R >> >> /Contents %s >>"
            % (contents if i == 0 else b"4 0 R")
        )
    out = bytearray(b"%PDF-1.4\n")
    offsets = []
    for n, body in enumerate(objs, 1):
        offsets.append(len(out))
        out += b"%d 0 obj\n%s\nendobj\n" % (n, body)
    xref = len(out)
    out += b"xref\n0 %d\n0000000000 65535 f \n" % (len(objs) + 1)
    out += b"".join(b"%010d 00000 n \n" % o for o in offsets)
    out += b"trailer\n<< /Size %d /Root 1 0 R >>\nstartxref\n%d\n%%%%EOF\n" % (len(objs) + 1, xref)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_bytes(bytes(out))
    return path

// A ROS 2 peer built on eProsima Fast DDS (Debian's libfastrtps 2.9, types from fastddsgen):
// ROS 2's default middleware, as a cross-vendor check of the live rover (Cyclone DDS).
//
// It subscribes to /rover/imu, /rover/odom, /rover/rgb/image_raw and /rover/lidar/points as a
// ROS 2 node on Fast DDS does (topics rt/<name>, types <pkg>::msg::dds_::<Type>_, sensor data
// best effort, odometry reliable), publishes geometry_msgs/Twist on /cmd_vel at 20 Hz, and
// prints one JSON line: samples per topic, first/last stamps, and what the last odometry said.
// Loopback only: UDPv4 on 127.0.0.1 (interface white list), no multicast, unicast discovery of
// 127.0.0.1 (participant ids 0..31).
//
// Usage: ros2_peer DOMAIN SECONDS V W [RECEIVE_BUFFER_BYTES]  (0 or absent: Fast DDS's default)

#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/dds/domain/DomainParticipantFactory.hpp>
#include <fastdds/dds/publisher/DataWriter.hpp>
#include <fastdds/dds/publisher/Publisher.hpp>
#include <fastdds/dds/subscriber/DataReader.hpp>
#include <fastdds/dds/subscriber/DataReaderListener.hpp>
#include <fastdds/dds/subscriber/SampleInfo.hpp>
#include <fastdds/dds/subscriber/Subscriber.hpp>
#include <fastdds/dds/topic/Topic.hpp>
#include <fastdds/rtps/transport/UDPv4TransportDescriptor.h>
#include <fastrtps/utils/IPLocator.h>

#include "ros2PubSubTypes.h"

using namespace eprosima::fastdds::dds;
namespace msg = sensor_msgs::msg::dds_;

struct Stats {
  std::mutex lock;
  long n = 0;
  double first = -1, last = -1;
  std::string note;
};

static double stamp(const std_msgs::msg::dds_::Header_& h) {
  return h.stamp().sec() + 1e-9 * h.stamp().nanosec();
}

template <class T>
class Counter : public DataReaderListener {
 public:
  explicit Counter(Stats* s, std::string (*describe)(const T&)) : s_(s), describe_(describe) {}
  void on_data_available(DataReader* reader) override {
    T sample;
    SampleInfo info;
    while (reader->take_next_sample(&sample, &info) == ReturnCode_t::RETCODE_OK) {
      if (!info.valid_data) continue;
      std::lock_guard<std::mutex> g(s_->lock);
      double t = stamp(sample.header());
      if (s_->n == 0) s_->first = t;
      s_->last = t;
      s_->n++;
      s_->note = describe_(sample);
    }
  }

 private:
  Stats* s_;
  std::string (*describe_)(const T&);
};

static std::string imu_note(const msg::Imu_& m) {
  char b[128];
  std::snprintf(b, sizeof b, "az=%.4f frame=%s", m.linear_acceleration().z(),
                m.header().frame_id().c_str());
  return b;
}
static std::string odom_note(const nav_msgs::msg::dds_::Odometry_& m) {
  char b[160];
  std::snprintf(b, sizeof b, "x=%.4f y=%.4f vx=%.4f child=%s", m.pose().pose().position().x(),
                m.pose().pose().position().y(), m.twist().twist().linear().x(),
                m.child_frame_id().c_str());
  return b;
}
static std::string image_note(const msg::Image_& m) {
  char b[128];
  std::snprintf(b, sizeof b, "%ux%u %s bytes=%zu", m.width(), m.height(), m.encoding().c_str(),
                m.data().size());
  return b;
}
static std::string cloud_note(const msg::PointCloud2_& m) {
  char b[128];
  std::snprintf(b, sizeof b, "points=%u fields=%zu point_step=%u bytes=%zu", m.width(),
                m.fields().size(), m.point_step(), m.data().size());
  return b;
}

int main(int argc, char** argv) {
  if (argc != 5 && argc != 6) {
    std::fprintf(stderr, "usage: ros2_peer DOMAIN SECONDS V W [RECEIVE_BUFFER_BYTES]\n");
    return 2;
  }
  const int domain = std::atoi(argv[1]);
  const double seconds = std::atof(argv[2]), v = std::atof(argv[3]), w = std::atof(argv[4]);

  DomainParticipantQos pqos;
  pqos.name("marsscene_fastdds_peer");
  auto udp = std::make_shared<eprosima::fastdds::rtps::UDPv4TransportDescriptor>();
  udp->interfaceWhiteList.push_back("127.0.0.1");
  if (argc == 6 && std::atol(argv[5]) > 0) udp->receiveBufferSize = std::atol(argv[5]);
  pqos.transport().use_builtin_transports = false;
  pqos.transport().user_transports.push_back(udp);
  auto& builtin = pqos.wire_protocol().builtin;
  builtin.metatrafficMulticastLocatorList.clear();
  eprosima::fastrtps::rtps::Locator_t peer;
  eprosima::fastrtps::rtps::IPLocator::setIPv4(peer, 127, 0, 0, 1);
  builtin.initialPeersList.push_back(peer);
  builtin.metatrafficUnicastLocatorList.clear();
  eprosima::fastrtps::rtps::Locator_t self;
  eprosima::fastrtps::rtps::IPLocator::setIPv4(self, 127, 0, 0, 1);
  builtin.metatrafficUnicastLocatorList.push_back(self);
  pqos.wire_protocol().default_unicast_locator_list.push_back(self);
  pqos.wire_protocol().participant_id = -1;
  builtin.discovery_config.leaseDuration_announcementperiod = eprosima::fastrtps::Duration_t(0, 500000000);

  auto* part = DomainParticipantFactory::get_instance()->create_participant(domain, pqos);
  if (part == nullptr) {
    std::fprintf(stderr, "cannot create a participant\n");
    return 1;
  }
  TypeSupport imu_t(new msg::Imu_PubSubType()), odom_t(new nav_msgs::msg::dds_::Odometry_PubSubType()),
      img_t(new msg::Image_PubSubType()), cloud_t(new msg::PointCloud2_PubSubType()),
      twist_t(new geometry_msgs::msg::dds_::Twist_PubSubType());
  for (auto* t : {&imu_t, &odom_t, &img_t, &cloud_t, &twist_t}) t->register_type(part);

  auto* sub = part->create_subscriber(SUBSCRIBER_QOS_DEFAULT);
  std::map<std::string, Stats> stats;
  DataReaderQos sensor = DATAREADER_QOS_DEFAULT, reliable = DATAREADER_QOS_DEFAULT;
  sensor.reliability().kind = BEST_EFFORT_RELIABILITY_QOS;
  sensor.history().kind = KEEP_LAST_HISTORY_QOS;
  sensor.history().depth = 5;
  sensor.endpoint().history_memory_policy = eprosima::fastrtps::rtps::PREALLOCATED_WITH_REALLOC_MEMORY_MODE;
  reliable.reliability().kind = RELIABLE_RELIABILITY_QOS;
  reliable.endpoint().history_memory_policy = eprosima::fastrtps::rtps::PREALLOCATED_WITH_REALLOC_MEMORY_MODE;

  Counter<msg::Imu_> imu_l(&stats["/rover/imu"], imu_note);
  Counter<nav_msgs::msg::dds_::Odometry_> odom_l(&stats["/rover/odom"], odom_note);
  Counter<msg::Image_> img_l(&stats["/rover/rgb/image_raw"], image_note);
  Counter<msg::PointCloud2_> cloud_l(&stats["/rover/lidar/points"], cloud_note);
  sub->create_datareader(part->create_topic("rt/rover/imu", imu_t.get_type_name(), TOPIC_QOS_DEFAULT), sensor, &imu_l);
  sub->create_datareader(part->create_topic("rt/rover/odom", odom_t.get_type_name(), TOPIC_QOS_DEFAULT), reliable, &odom_l);
  sub->create_datareader(part->create_topic("rt/rover/rgb/image_raw", img_t.get_type_name(), TOPIC_QOS_DEFAULT), sensor, &img_l);
  sub->create_datareader(part->create_topic("rt/rover/lidar/points", cloud_t.get_type_name(), TOPIC_QOS_DEFAULT), sensor, &cloud_l);

  auto* pub = part->create_publisher(PUBLISHER_QOS_DEFAULT);
  DataWriterQos wq = DATAWRITER_QOS_DEFAULT;
  wq.reliability().kind = RELIABLE_RELIABILITY_QOS;
  auto* cmd = pub->create_datawriter(part->create_topic("rt/cmd_vel", twist_t.get_type_name(), TOPIC_QOS_DEFAULT), wq);

  geometry_msgs::msg::dds_::Twist_ twist;
  twist.linear().x(v);
  twist.angular().z(w);
  long sent = 0;
  const auto t0 = std::chrono::steady_clock::now();
  while (std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() < seconds) {
    cmd->write(&twist);
    sent++;
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  std::printf("{\"cmd_vel_sent\": %ld", sent);
  for (auto& [name, s] : stats) {
    std::lock_guard<std::mutex> g(s.lock);
    std::printf(", \"%s\": {\"n\": %ld, \"first\": %.3f, \"last\": %.3f, \"last_sample\": \"%s\"}",
                name.c_str(), s.n, s.first, s.last, s.note.c_str());
  }
  std::printf("}\n");
  std::fflush(stdout);
  std::_Exit(0);  // the readers' listeners live on the stack: leave without tearing down
}

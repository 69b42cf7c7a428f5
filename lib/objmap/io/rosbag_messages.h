#pragma once
// The ROS messages io/rosbag.cpp reads, as read from a bag that may be damaged: private to
// rosbag.cpp (include it from nowhere else; it needs rosbag_storage's headers).
//
// ROS's readers size an array to the length its message claims (up to 2^32 elements) before they
// find that the message is shorter: a damaged image message claiming gigabytes of pixels costs
// seconds and gigabytes before it fails. The Checked* messages are the ROS messages of the same
// MD5 sum (a bag's connection of that type gives them) read field by field, each array's length
// checked against the bytes left in the message first: a StreamOverrunException (a
// ros::Exception, named by rosbag.cpp as a damaged bag) instead.
#include <cstdint>
#include <cstring>
#include <string>
#include <type_traits>

#include <ros/serialization.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/CompressedImage.h>
#include <sensor_msgs/Image.h>
#include <std_msgs/Header.h>
#include <tf2_msgs/TFMessage.h>

namespace objmap_rosbag {

// The header of an Image or CompressedImage alone (both start with it): the stamps of a stream are
// read without copying its pixels.
struct StampOnly {
  std_msgs::Header header;
};

struct CheckedImage : sensor_msgs::Image {};
struct CheckedCompressedImage : sensor_msgs::CompressedImage {};
struct CheckedCameraInfo : sensor_msgs::CameraInfo {};
struct CheckedTFMessage : tf2_msgs::TFMessage {};

// The fewest bytes a geometry_msgs/TransformStamped takes: its header (seq, stamp, an empty
// frame_id), an empty child_frame_id, and the seven doubles of its transform.
constexpr std::uint64_t kMinTransformStampedBytes = 4 + 8 + 4 + 4 + 7 * 8;

// A length-prefixed array of `v`'s elements, each at least `element_bytes` long: its length
// checked against what is left of the message before the array is sized.
template <typename Stream, typename Vector>
void next_array(Stream& stream, Vector& v, std::uint64_t element_bytes, const char* field) {
  std::uint32_t n = 0;
  stream.next(n);
  const std::uint64_t left = stream.getLength();
  if (std::uint64_t{n} * element_bytes > left)
    throw ros::serialization::StreamOverrunException(
        std::string("damaged message: its ") + field + " claims " + std::to_string(n) +
        (element_bytes == 1 ? " bytes"
                            : " elements of at least " + std::to_string(element_bytes) + " bytes") +
        " with " + std::to_string(left) +
        " bytes left in the message; expected a complete message");
  v.resize(n);
  using Element = typename Vector::value_type;
  if constexpr (std::is_same_v<Element, std::uint8_t>) {
    if (n > 0) std::memcpy(v.data(), stream.advance(n), n);
  } else {
    for (Element& e : v) stream.next(e);
  }
}

}  // namespace objmap_rosbag

// The ROS traits: StampOnly matches any message ("*"); a Checked* message is its base's type.
namespace ros::message_traits {
template <>
struct MD5Sum<objmap_rosbag::StampOnly> {
  static const char* value() { return "*"; }
  static const char* value(const objmap_rosbag::StampOnly&) { return value(); }
};
template <>
struct DataType<objmap_rosbag::StampOnly> {
  static const char* value() { return "*"; }
  static const char* value(const objmap_rosbag::StampOnly&) { return value(); }
};
template <>
struct Definition<objmap_rosbag::StampOnly> {
  static const char* value() { return ""; }
  static const char* value(const objmap_rosbag::StampOnly&) { return value(); }
};

#define OBJMAP_CHECKED_MESSAGE_TRAITS(Checked, Base)                 \
  template <>                                                        \
  struct MD5Sum<Checked> {                                           \
    static const char* value() { return MD5Sum<Base>::value(); }     \
    static const char* value(const Checked&) { return value(); }     \
  };                                                                 \
  template <>                                                        \
  struct DataType<Checked> {                                         \
    static const char* value() { return DataType<Base>::value(); }   \
    static const char* value(const Checked&) { return value(); }     \
  };                                                                 \
  template <>                                                        \
  struct Definition<Checked> {                                       \
    static const char* value() { return Definition<Base>::value(); } \
    static const char* value(const Checked&) { return value(); }     \
  };
OBJMAP_CHECKED_MESSAGE_TRAITS(objmap_rosbag::CheckedImage, sensor_msgs::Image)
OBJMAP_CHECKED_MESSAGE_TRAITS(objmap_rosbag::CheckedCompressedImage, sensor_msgs::CompressedImage)
OBJMAP_CHECKED_MESSAGE_TRAITS(objmap_rosbag::CheckedCameraInfo, sensor_msgs::CameraInfo)
OBJMAP_CHECKED_MESSAGE_TRAITS(objmap_rosbag::CheckedTFMessage, tf2_msgs::TFMessage)
#undef OBJMAP_CHECKED_MESSAGE_TRAITS
}  // namespace ros::message_traits

// The readers, field by field in each message's order (sensor_msgs/Image.msg and the others).
namespace objmap_rosbag {

template <typename Stream>
void read_fields(Stream& stream, StampOnly& m) {
  stream.next(m.header);
}

// Image and CameraInfo begin alike: header, height, width.
template <typename Stream, typename Message>
void read_sized_header(Stream& stream, Message& m) {
  stream.next(m.header);
  stream.next(m.height);
  stream.next(m.width);
}

template <typename Stream>
void read_fields(Stream& stream, CheckedImage& m) {
  read_sized_header(stream, m);
  stream.next(m.encoding);
  stream.next(m.is_bigendian);
  stream.next(m.step);
  next_array(stream, m.data, 1, "image data");
}

template <typename Stream>
void read_fields(Stream& stream, CheckedCompressedImage& m) {
  stream.next(m.header);
  stream.next(m.format);
  next_array(stream, m.data, 1, "compressed image data");
}

template <typename Stream>
void read_fields(Stream& stream, CheckedCameraInfo& m) {
  read_sized_header(stream, m);
  stream.next(m.distortion_model);
  next_array(stream, m.D, sizeof(double), "distortion D");
  stream.next(m.K);
  stream.next(m.R);
  stream.next(m.P);
  stream.next(m.binning_x);
  stream.next(m.binning_y);
  stream.next(m.roi);
}

template <typename Stream>
void read_fields(Stream& stream, CheckedTFMessage& m) {
  next_array(stream, m.transforms, kMinTransformStampedBytes, "transforms");
}

}  // namespace objmap_rosbag

// ROS reads a message through its Serializer: each of these through its read_fields above.
namespace ros::serialization {
#define OBJMAP_READ_THROUGH_FIELDS(Message)        \
  template <>                                      \
  struct Serializer<Message> {                     \
    template <typename Stream>                     \
    static void read(Stream& stream, Message& m) { \
      objmap_rosbag::read_fields(stream, m);       \
    }                                              \
  };
OBJMAP_READ_THROUGH_FIELDS(objmap_rosbag::StampOnly)
OBJMAP_READ_THROUGH_FIELDS(objmap_rosbag::CheckedImage)
OBJMAP_READ_THROUGH_FIELDS(objmap_rosbag::CheckedCompressedImage)
OBJMAP_READ_THROUGH_FIELDS(objmap_rosbag::CheckedCameraInfo)
OBJMAP_READ_THROUGH_FIELDS(objmap_rosbag::CheckedTFMessage)
#undef OBJMAP_READ_THROUGH_FIELDS
}  // namespace ros::serialization

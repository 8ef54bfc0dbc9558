#include <duet_ros/params.hpp>

#include <sstream>

namespace duet_ros {

void read_sets(const ros::NodeHandle& pnh, std::vector<std::string>& out) {
  if (!pnh.hasParam("set")) return;
  XmlRpc::XmlRpcValue v;
  pnh.getParam("set", v);
  if (v.getType() == XmlRpc::XmlRpcValue::TypeArray) {
    for (int i = 0; i < v.size(); ++i) {
      require(v[i].getType() == XmlRpc::XmlRpcValue::TypeString, "~set[" + std::to_string(i) + "]: not a string KEY=VALUE");
      out.push_back(static_cast<std::string>(v[i]));
    }
    return;
  }
  require(v.getType() == XmlRpc::XmlRpcValue::TypeString, "~set: neither a list of KEY=VALUE strings nor one string of them separated by ';'");
  std::stringstream ss(static_cast<std::string>(v));
  for (std::string item; std::getline(ss, item, ';');)
    if (item.find_first_not_of(" \t") != std::string::npos) out.push_back(item);
}

}  // namespace duet_ros

// Model files: JSON with a versioned schema ("plsa.dio_pwl_obf", version 1)
// holding units, sample time, column names, poles, partition and
// coefficients. Loading validates all of it and names what is wrong.
#pragma once

#include <string>

#include "plsa/model/dio_pwl_obf_model.hpp"

namespace plsa {

std::string modelToJson(const DioPwlObfModel& model);
DioPwlObfModel modelFromJson(const std::string& text, const std::string& source = "<json>");
void saveModel(const std::string& path, const DioPwlObfModel& model);
DioPwlObfModel loadModel(const std::string& path);

}  // namespace plsa

// Model files: JSON with a versioned schema ("plsa.dio_pwl_obf"; this build
// writes version 2 and reads 1 and 2; schemas/model.schema.json) holding
// units, sample time, column names, poles, input shaping, partition and
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

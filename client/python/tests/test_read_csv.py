"""`read_imu_csv`: a log it cannot read says where and what, as the Rust reader does."""

import math
import os
import tempfile
import unittest

from corridor_client.producer import read_imu_csv

HEADER = "t_s,gx_rad_s,gy_rad_s,gz_rad_s,ax_m_s2,ay_m_s2,az_m_s2,temp_c\n"


def write(text: str) -> str:
    fd, path = tempfile.mkstemp(suffix=".csv")
    with os.fdopen(fd, "w", encoding="utf-8") as f:
        f.write(text)
    return path


class ReadImuCsv(unittest.TestCase):
    def test_a_bom_and_a_temperature_that_is_no_number_are_read(self) -> None:
        path = write("\ufeff" + HEADER + "0.0,0,0,0,0,0,9.8,n/a\n0.01,0,0,0,0,0,9.8,21.5\n")
        rows = list(read_imu_csv(path))
        os.remove(path)
        self.assertEqual(len(rows), 2)
        self.assertTrue(math.isnan(rows[0].temp_c))
        self.assertEqual(rows[1].temp_c, 21.5)

    def test_a_field_that_is_no_number_is_named_with_its_line_and_column(self) -> None:
        path = write(HEADER + "0.0,0,0,0,0,0,9.8,20\n0.01,0,x,0,0,0,9.8,20\n")
        with self.assertRaises(ValueError) as e:
            list(read_imu_csv(path))
        os.remove(path)
        self.assertIn(f"{path}:3: column gy_rad_s: 'x' is no number", str(e.exception))

    def test_a_missing_column_is_named(self) -> None:
        path = write("t_s,gx_rad_s\n0.0,0\n")
        with self.assertRaises(ValueError) as e:
            list(read_imu_csv(path))
        os.remove(path)
        self.assertIn("no column gy_rad_s", str(e.exception))


if __name__ == "__main__":
    unittest.main()

//! STM32F446RE Nucleo-64 board.

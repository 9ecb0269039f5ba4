# SPDX-License-Identifier: BSD-3-Clause
# manpage.awk - the man page from its template, doc/sandslide.1.in:
#
#   awk -v program=build/sandslide -f doc/manpage.awk doc/sandslide.1.in > build/sandslide.1
#
# (the Makefile's rule).  The template is man(7) roff written by hand, with
# one block in each command's section where its options go:
#
#   .\" @options CMD
#   .\" @note --NAME
#   roff said of --NAME after its entry (what its table does not say)
#   .\" @end
#
# The block becomes the output of `program help --roff CMD`: each option of
# `sandslide CMD --help` as a .TP entry and each heading of it as a
# paragraph, from the option tables (src/cli/options.c), with each note
# after its option's entry as a paragraph of its own.  Everything else is
# copied.  A note for an option the command does not list, two notes for
# one, a block not closed, or the program failing is an error: no page.
# POSIX awk (Debian's mawk).

function fail(message) {
	printf "%s:%d: %s\n", FILENAME, FNR, message > "/dev/stderr"
	failed = 1
	exit 1
}

# The note of the entry just printed, if any, as a paragraph under it.
function flush() {
	if (entry != "" && (entry in note)) {
		print ".IP"
		printf "%s", note[entry]
		used[entry] = 1
	}
	entry = ""
}

function expand(command,   run, line, got, name) {
	run = "'" program "' help --roff " command
	entry = ""
	while ((got = (run | getline line)) > 0) {
		if (line ~ /^\.\\" (option|heading)/) {   # where an item starts
			flush()
			if (line ~ /^\.\\" option /)
				entry = substr(line, length(".\\\" option ") + 1)
			continue
		}
		print line
	}
	flush()
	if (got < 0 || close(run) != 0)
		fail("`" run "` failed")
	for (name in note)
		if (!(name in used))
			fail("a note for " name ", which `" run "` does not list")
}

BEGIN {
	if (program == "") {
		print "usage: awk -v program=PATH/sandslide -f manpage.awk TEMPLATE" > "/dev/stderr"
		failed = 1
		exit 2
	}
	print ".\\\" Made by make from doc/sandslide.1.in and the option tables"
	print ".\\\" (doc/manpage.awk): edit those, not this."
}

/^\.\\" @options / {
	if (command != "")
		fail("@options inside the block of " command)
	command = $3
	if (command == "")
		fail("@options names no command")
	split("", note)
	split("", used)
	key = ""
	next
}

/^\.\\" @note / {
	if (command == "")
		fail("@note outside an @options block")
	key = $3
	if (key in note)
		fail("two notes for " key)
	note[key] = ""
	next
}

/^\.\\" @end/ {
	if (command == "")
		fail("@end without @options")
	expand(command)
	command = key = ""
	next
}

/^\.\\" @/ {
	fail("unknown directive: " $0)
}

command != "" {
	if (key == "")
		fail("text in the block of " command " before its first @note")
	note[key] = note[key] $0 "\n"
	next
}

{ print }

END {
	if (!failed && command != "")
		fail("the block of " command " has no @end")
	if (failed)
		exit 1
}

;;;; tools/one-process.lisp -- the start every one-process tool shares (tools/against-one.lisp for
;;;; make bench-against and make count-against, tools/feature-one.lisp for make count-features):
;;;; put off collections when asked, check the arguments, load the engine of the tree they name.

(defun one-process-arguments (tool usage count)
  "The COUNT command-line arguments of the tool TOOL, after loading the engine of the tree whose
directory is the first of them; the process ends, printing USAGE, when there are not COUNT.
When AGAINST_NURSERY_BYTES is set (make count-against and make count-features run the tools
under valgrind, where a collection's signals stop the run), no collection starts before that
many bytes are consed."
  (let ((bytes (sb-ext:posix-getenv "AGAINST_NURSERY_BYTES")))
    (when (and bytes (plusp (length bytes)))
      (setf (sb-ext:bytes-consed-between-gcs) (parse-integer bytes))))
  (let ((arguments (rest sb-ext:*posix-argv*)))
    (unless (= count (length arguments))
      (format *error-output* "~A: usage: ~A.lisp ~A~%" tool tool usage)
      (sb-ext:exit :code 2))
    (load (concatenate 'string (first arguments) "tools/boot.lisp"))
    ;; the tree's workshop, where the benchmarks live; a tree from before the workshop was a
    ;; system of its own has them in luv-physics
    (when (funcall 'luv-load-systems (if (funcall (find-symbol "FIND-SYSTEM" "ASDF") "luv-physics/workshop" nil)
                                         "luv-physics/workshop"
                                         "luv-physics"))
      (sb-ext:exit :code 2))
    arguments))
